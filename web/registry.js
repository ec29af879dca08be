// Registry: search offices, look up pincodes and keys; admins add and retire pincodes, edit the
// sort plans (plans.js) and manage the API tokens (tokens.js).
import {
  api, query, el, show, problemBox, messageBox, badge, busy, bindToken, isPincode, pincodeFieldValue, confirmBox, utcMinute,
} from './api.js';
import { setUpSortPlans } from './plans.js';
import { setUpTokens } from './tokens.js';

const $ = (id) => document.getElementById(id);

let forgetTokens = null;  // set below: Forget takes the token list and any new secret shown too
const token = bindToken({
  name: 'admin', input: $('token'), status: $('token-status'), forget: $('token-forget'), toggle: $('token-toggle'),
  onForget: () => forgetTokens?.(),
});

let search = null;  // {q, district, state, limit, offset}

// Every change needs an admin token: asked for before anything is sent or confirmed.
function needToken(message) {
  if (token()) return false;
  show(message, messageBox('info', 'Paste an admin token above first: changes to the registry, sort plans and tokens need one.'));
  $('token').focus();
  return true;
}

// The pincode fields have no maxlength: a browser cuts a pasted value to it before the page sees
// it, so a pasted 5600012 became 560001, another real pincode, and " 560001" lost its last digit.
// What was typed or pasted is checked whole instead.
function notAPincode(text) {
  // What is wrong with this one, not only the rule: "(this is 6 characters)" under 099010 read as
  // if six were the fault.
  const length = [...text].length;
  const why = /^[0-9]{6}$/.test(text) ? 'it starts with 0'
    : /^[0-9]*$/.test(text) ? `it has ${length} ${length === 1 ? 'digit' : 'digits'}`
      : 'it holds a character that is not a digit';
  return { title: 'Not a pincode',
    message: `“${text}” is not a pincode: a pincode is six digits, the first 1–9, and ${why}.` };
}

// Keys as the server reads them: digits, 0–32767 (leading zeros allowed).
function notAKey(text) {
  if (/^[0-9]+$/.test(text) && Number(text) <= 32767) return null;
  return { title: 'Not a key',
    message: text ? `“${text}” is not a key: a key is a whole number from 0 to 32767.` : 'Fill in a key, 0–32767.' };
}

// A search shown while a pincode is added or retired would show its old status: drawn again.
function refreshSearch() {
  if (search && !$('search-results').hidden) runSearch();
}

// `clicked`: the office whose row of a search was clicked, when that is not the pincode's own
// office (the one a label prints unless another is chosen): it is named first, and marked in the
// list of offices, which is opened. The card showed only the pincode's own office, so a click on
// Connaught Place showed Bengali Market.
function showRecord(record, note, clicked = null) {
  // A search's refusal beside the Search button is old news once another record is shown.
  show($('search-msg'));
  const offices = record.offices || [];
  const other = clicked && clicked !== record.office ? offices.find((o) => o.name === clicked) : null;
  show($('detail'),
    note ? messageBox('ok', note) : null,
    el('div', { class: 'row record-head' },
      el('span', { class: 'big-pin', id: 'detail-pincode' }, record.pincode), badge(record.status)),
    el('dl', { class: 'kv' },
      [['Key', el('span', { id: 'detail-key', class: 'mono' }, String(record.key))],
        other ? ['Office chosen', el('span', { id: 'detail-chosen-office' }, el('bdi', {}, other.name), ', ',
          el('bdi', {}, other.district), ', ', el('bdi', {}, other.state))] : null,
        [other ? 'Main office' : 'Office', record.office || '—'],
        ['District', record.district || '—'], ['State', record.state || '—'], ['Division', record.division || '—'],
        ['Region', record.region || '—'], ['Circle', record.circle || '—'],
        record.retired_at ? ['Retired', utcMinute(record.retired_at)] : null]
        .filter(Boolean).map(([name, value]) => [el('dt', {}, name), el('dd', {}, value)])),
    other ? el('p', { class: 'small muted' },
      'A label for this pincode prints its main office unless the counter chooses another.') : null,
    offices.length > 1 ? el('details', { class: 'more space-above-md', open: other ? true : null },
      el('summary', {}, `All ${offices.length} offices`),
      el('ul', { class: 'small' }, offices.map((o) => el('li', { 'aria-current': o === other ? 'true' : null },
        o === other ? el('strong', {}, el('bdi', {}, o.name)) : el('bdi', {}, o.name), ' — ', el('bdi', {}, o.district))))) : null);
}

// The details card is far below a long result list (thousands of pixels on a phone): bring it
// into view, or a click on a pincode looks as if it did nothing.
function revealDetail() {
  $('detail-card').scrollIntoView({ block: 'nearest' });
}

// Only the latest request for the details card draws in it: a slow answer for one pincode came
// after a click on another and replaced it. Each request takes a number; an answer whose number
// is no longer the latest is dropped.
let detailRequest = 0;
function claimDetail() {
  detailRequest += 1;
  const request = detailRequest;
  return () => request === detailRequest;
}

// `besideSearch`: a pincode searched for, whose refusal is said beside the Search button (on a
// phone the details card is far below it) and once: the card keeps a plain note, not a second
// alert for a screen reader to announce.
async function showPincode(pin, { besideSearch = false, office = null } = {}) {
  const latest = claimDetail();
  try {
    const record = await api(`/api/v1/pincodes/${pin}`);
    if (latest()) showRecord(record, null, office);
  } catch (error) {
    if (!latest()) return;
    if (!besideSearch) {
      show($('detail'), problemBox(error));
      return;
    }
    show($('search-msg'), problemBox(error));
    show($('detail'), el('p', { class: 'muted' }, `${pin}: ${error.title || 'not found'} (see beside Search).`));
  }
}

let searchRequest = 0;  // only the latest search's answer is drawn

// Previous and Next are off while a page loads; the answer sets them (not `busy`, which would put
// back what they were before the click).
async function runSearch() {
  const request = ++searchRequest;
  $('prev').disabled = true;
  $('next').disabled = true;
  show($('search-msg'));
  try {
    const asked = search;
    const page = await api(`/api/v1/pincodes${query(asked)}`);
    if (request !== searchRequest) return;
    const body = $('results-body');
    show(body, page.results.map((hit) => el('tr', {},
      el('td', { class: 'mono nowrap' },
        el('button', { type: 'button', class: 'link', onclick: () => showPincode(hit.pincode, { office: hit.office.name }).then(revealDetail),
          'aria-label': `Details of ${hit.pincode}` }, hit.pincode)),
      el('td', {}, hit.office.name),
      el('td', {}, hit.office.district),
      el('td', { class: 'hide-narrow' }, hit.office.state),
      el('td', { class: 'num mono hide-narrow' }, hit.key),
      el('td', {}, badge(hit.status)))));
    const first = page.total === 0 ? 0 : page.offset + 1;
    const last = page.offset + page.results.length;
    const pages = Math.max(1, Math.ceil(page.total / page.limit));
    const current = Math.floor(page.offset / page.limit) + 1;
    const whole = asked.district || asked.state
      ? ' A district or state is matched whole and as the registry spells it, which may be an older name (Bangalore, not Bengaluru); an office name by its first letters.'
      : '';
    $('results-caption').textContent = page.total === 0
      ? `No office matches.${whole}` : `Offices ${first}–${last} of ${page.total}`;
    $('page-info').textContent = `Page ${current} of ${pages}`;
    $('prev').disabled = page.offset === 0;
    $('next').disabled = last >= page.total;
    $('search-results').hidden = false;
  } catch (error) {
    if (request !== searchRequest) return;
    $('search-results').hidden = true;
    show($('search-msg'), problemBox(error));
  }
}

$('search-form').addEventListener('submit', (event) => {
  event.preventDefault();
  // "११०००१" typed on a Hindi keyboard, "110 001" as a label prints it
  const pin = pincodeFieldValue($('s-pin').value);
  busy($('search'), async () => {
    if (pin) {
      if (!isPincode(pin)) {
        show($('search-msg'), problemBox(notAPincode(pin)));
        return;
      }
      show($('search-msg'));
      // The list of an earlier search goes (and one still loading is dropped): left on screen it
      // read as this search's answer ("No office matches." under a pincode that exists).
      ++searchRequest;
      search = null;
      $('search-results').hidden = true;
      await showPincode(pin, { besideSearch: true });
      revealDetail();
      return;
    }
    const asked = { q: $('s-q').value.trim(), district: $('s-district').value.trim(), state: $('s-state').value.trim(),
      limit: Number($('s-limit').value), offset: 0 };
    // Not kept when empty: a later change of the page size would run it and show the server's 400.
    if (!asked.q && !asked.district && !asked.state) {
      show($('search-msg'), messageBox('info', 'Fill in a pincode, an office name, a district or a state.'));
      return;
    }
    search = asked;
    await runSearch();
  });
});
$('prev').addEventListener('click', () => {
  search.offset = Math.max(0, search.offset - search.limit);
  runSearch();
});
$('next').addEventListener('click', () => {
  search.offset += search.limit;
  runSearch();
});
// A new page size applies to the search at once, shown or still loading, keeping the first row
// shown in view.
$('s-limit').addEventListener('change', (event) => {
  if (!search) return;
  search.limit = Number(event.currentTarget.value);
  search.offset = Math.floor(search.offset / search.limit) * search.limit;
  runSearch();
});

$('key-form').addEventListener('submit', (event) => {
  event.preventDefault();
  const key = $('key').value.trim();
  const wrong = notAKey(key);
  if (wrong) {
    show($('key-msg'), problemBox(wrong));
    return;
  }
  busy($('key-lookup'), async () => {
    show($('key-msg'));
    const latest = claimDetail();
    try {
      const record = await api(`/api/v1/keys/${encodeURIComponent(key)}`);
      if (latest()) showRecord(record);
      const where = record.office || record.district;
      // The office's name isolated, as in every sentence holding the server's names: written right
      // to left, it took the brackets and words around it into its own order.
      show($('key-msg'), messageBox('ok', `Key ${key} belongs to ${record.pincode}`,
        where ? [' (', el('bdi', {}, where), ')'] : null, '.'));
    } catch (error) {
      show($('key-msg'), problemBox(error));
    }
  });
});

// The fields a refusal is about are marked invalid and pointed at the message that says why, so a
// screen reader announces it on the field and the field shows it (red border); the rest unmarked.
function markInvalid(form, message, ids) {
  for (const input of form.querySelectorAll('input')) {
    if (ids.includes(input.id)) {
      input.setAttribute('aria-invalid', 'true');
      input.setAttribute('aria-describedby', message.id);
    } else {
      input.removeAttribute('aria-invalid');
      input.removeAttribute('aria-describedby');
    }
  }
}

$('add-form').addEventListener('submit', (event) => {
  event.preventDefault();
  busy($('add'), async () => {
    show($('add-msg'));
    markInvalid($('add-form'), $('add-msg'), []);
    const value = (id) => (id === 'a-pin' ? pincodeFieldValue($(id).value) : $(id).value.trim());
    if (needToken($('add-msg'))) return;
    if (!isPincode(value('a-pin'))) {
      show($('add-msg'), problemBox(notAPincode(value('a-pin'))));
      markInvalid($('add-form'), $('add-msg'), ['a-pin']);
      return;
    }
    const body = { pincode: value('a-pin') };
    // Any office field filled sends the office with every required field, blank ones too: the
    // server then names each one missing, and nothing typed is dropped.
    const required = [['name', 'a-office'], ['district', 'a-district'], ['state', 'a-state'],
      ['division', 'a-division'], ['region', 'a-region'], ['circle', 'a-circle']];
    if ([...required, ['branch_type', 'a-branch']].some(([, id]) => value(id))) {
      const office = Object.fromEntries(required.map(([field, id]) => [field, value(id)]));
      if (value('a-branch')) office.branch_type = value('a-branch');
      body.offices = [office];
    }
    const latest = claimDetail();
    try {
      const record = await api('/api/v1/pincodes', { method: 'POST', token: token(), json: body });
      show($('add-msg'), messageBox('ok', 'Added ', el('strong', {}, record.pincode), ' with key ',
        el('strong', { id: 'added-key' }, String(record.key)), '.'));
      if (latest()) showRecord(record, `Pincode ${record.pincode} added.`);
      refreshSearch();
    } catch (error) {
      show($('add-msg'), problemBox(error));
      // An office refused for its empty fields: those fields. A pincode already there: the pincode.
      if (error.status === 400 && body.offices) {
        markInvalid($('add-form'), $('add-msg'), required.filter(([, id]) => !value(id)).map(([, id]) => id));
      } else if (error.status === 409) {
        markInvalid($('add-form'), $('add-msg'), ['a-pin']);
      }
    }
  });
});

$('retire-form').addEventListener('submit', (event) => {
  event.preventDefault();
  const pin = pincodeFieldValue($('r-pin').value);
  show($('retire-msg'));
  show($('retire-confirm'));
  if (needToken($('retire-msg'))) return;
  if (!isPincode(pin)) {
    show($('retire-msg'), problemBox(notAPincode(pin)));
    return;
  }
  busy($('retire'), async () => {
    let record;
    try {
      record = await api(`/api/v1/pincodes/${encodeURIComponent(pin)}`);
    } catch (error) {
      show($('retire-msg'), problemBox(error));
      return;
    }
    if (record.status === 'retired') {
      show($('retire-msg'), messageBox('info', `${pin} is already retired.`));
      return;
    }
    // The box goes with the buttons: focus goes back to the pincode field, not to the page's top.
    const close = () => { show($('retire-confirm')); $('r-pin').focus(); };
    const where = record.office || record.district;
    const { box, noButton } = confirmBox({
      label: 'Confirm retiring',
      message: [`Retire ${pin} (`, where ? [el('bdi', {}, where), ', '] : null,
        `key ${record.key})? No new labels will be issued for it.`],
      yes: `Retire ${pin}`,
      yesId: 'retire-yes',
      onNo: close,
      onYes: async () => {
        const latest = claimDetail();
        try {
          const retired = await api(`/api/v1/pincodes/${pin}/retire`, { method: 'POST', token: token() });
          show($('retire-confirm'));
          show($('retire-msg'), messageBox('ok', `${pin} is retired. It keeps key ${retired.key}.`));
          if (latest()) showRecord(retired);
          refreshSearch();
          $('r-pin').focus();
        } catch (error) {
          show($('retire-msg'), problemBox(error));
        }
      },
    });
    show($('retire-confirm'), box);
    // Focus on Cancel: retiring cannot be undone, and the Enter that opened the box, pressed
    // again, must not be what retires a mistyped pincode.
    noButton.focus();
  });
});

setUpSortPlans({ token, needToken });
forgetTokens = setUpTokens({ token, needToken });
