// Sort plans on the registry page: list them, open one as CSV text, save it back (conditionally,
// so one admin's save never undoes another's), create, delete with an undo, and route a pincode
// by the plan as saved. The server checks every plan; the page shows its problem as it says it.
import { api, el, show, problemBox, messageBox, busy, isPincode, asciiDigits } from './api.js';

const $ = (id) => document.getElementById(id);

const kNewPlanText = 'prefix,bin\n*,manual\n';

// A PUT of CSV keeps the stored description unless ?description= is given; the page always gives
// the field's value, so clearing the field clears it.
function planPath(name, params = '') {
  return `/api/v1/sortplans/${encodeURIComponent(name)}${params}`;
}

// The version digits of an ETag, either form ("<hex>" on JSON, "<hex>-csv" on CSV).
function versionOf(etag) {
  return (etag || '').replace(/^"|"$/g, '').replace(/-csv$/, '');
}

/**
 * Sets up the sort plan section. `token()` gives the admin token; `needToken(messageBox)` says
 * one is missing (and returns true) before anything is sent.
 */
export function setUpSortPlans({ token, needToken }) {
  // What is open: the plan's name as stored, the version it was read at (null for a new plan),
  // and the text and description as read, to tell whether the fields hold unsaved changes.
  let open = null;

  const fields = { name: $('p-name'), description: $('p-description'), rules: $('p-rules'), pincode: $('p-try') };
  const dirty = () => open !== null &&
    (fields.rules.value !== open.text || fields.description.value !== open.description ||
      (open.version === null && fields.name.value.trim() !== ''));

  let listFailed = false;
  async function listPlans() {
    try {
      const { plans } = await api('/api/v1/sortplans');
      show($('plans-body'), plans.map((plan) => el('tr', { class: open && open.name === plan.name ? 'is-selected' : null },
        el('td', {}, el('button', { type: 'button', class: 'link', onclick: () => askToOpen(plan.name),
          'aria-label': `Open plan ${plan.name}` }, el('bdi', {}, plan.name))),
        el('td', {}, el('bdi', {}, plan.fallback_bin)),
        el('td', { class: 'num' }, String(plan.rules)),
        el('td', { class: 'hide-narrow' }, plan.description ? el('bdi', {}, plan.description) : '—'))));
      $('plans-caption').textContent = plans.length === 1 ? '1 plan' : `${plans.length} plans`;
      // Only the list's own problem goes with a list read again; a deletion's note stays.
      if (listFailed) show($('plans-msg'));
      listFailed = false;
    } catch (error) {
      $('plans-caption').textContent = 'The plans could not be read.';
      show($('plans-msg'), problemBox(error));
      listFailed = true;
    }
  }

  // The JSON (description) and the CSV (the text edited) are read together; the two answers must
  // name one version, or a save in between mixed two. Read again when they do not.
  async function readPlan(name) {
    for (let attempt = 0; ; ++attempt) {
      const [json, csv] = await Promise.all([
        api(planPath(name), { as: 'response' }),
        api(planPath(name, '?format=csv'), { as: 'response', headers: { Accept: 'text/csv' } }),
      ]);
      const version = versionOf(json.headers.get('ETag'));
      if (version === versionOf(csv.headers.get('ETag')) || attempt === 2) {
        const plan = await json.json();
        return { plan, text: await csv.text(), version };
      }
    }
  }

  function showEditor(state, heading) {
    open = state;
    $('plan-form').hidden = false;
    $('plan-edit-h').textContent = heading;
    fields.name.value = state.name;
    fields.name.readOnly = state.version !== null;
    fields.description.value = state.description;
    fields.rules.value = state.text;
    const saved = state.version !== null;
    $('plan-csv').hidden = !saved;
    if (saved) {
      $('plan-csv').href = planPath(state.name, '?format=csv');
      $('plan-csv').setAttribute('download', `${state.name}.csv`);
    }
    // The default plan serves every label and scan that names none: the server never deletes it.
    $('plan-delete').hidden = !saved || state.name === 'default';
    $('plan-try').hidden = !saved;
    show($('plan-confirm'));
    show($('plan-route-msg'));
    for (const row of $('plans-body').querySelectorAll('tr')) {
      row.classList.toggle('is-selected', row.querySelector('bdi')?.textContent === state.name && saved);
    }
  }

  async function openPlan(name, note) {
    show($('plan-msg'));
    try {
      const { plan, text, version } = await readPlan(name);
      showEditor({ name: plan.name, version, text, description: plan.description || '' }, `Plan ${plan.name}`);
      show($('plan-msg'), note || null);
      $('plan-form').scrollIntoView({ block: 'nearest' });
    } catch (error) {
      show($('plans-msg'), problemBox(error));
      if (error.status === 404) listPlans();
    }
  }

  // Opening another plan over unsaved changes would drop them: asked first.
  function askToOpen(name, opener = () => openPlan(name)) {
    if (!dirty()) {
      opener();
      return;
    }
    const discard = el('button', { type: 'button', class: 'danger', id: 'plan-discard' }, 'Discard my changes');
    const keep = el('button', { type: 'button', class: 'secondary' }, 'Keep editing');
    discard.addEventListener('click', () => { open = null; show($('plan-confirm')); opener(); });
    keep.addEventListener('click', () => { show($('plan-confirm')); fields.rules.focus(); });
    show($('plan-confirm'), el('div', { class: 'alert alert-info', role: 'alertdialog', 'aria-label': 'Unsaved changes' },
      el('p', {}, 'The plan being edited has unsaved changes.'),
      el('div', { class: 'actions' }, discard, keep)));
    discard.focus();
  }

  function newPlan() {
    showEditor({ name: '', version: null, text: kNewPlanText, description: '' }, 'New plan');
    show($('plan-msg'));
    fields.name.focus();
  }

  async function save() {
    show($('plan-msg'));
    show($('plan-confirm'));
    if (needToken($('plan-msg'))) return;
    const name = open.version === null ? fields.name.value.trim() : open.name;
    if (!name) {
      show($('plan-msg'), problemBox({ title: 'No name', message: 'Give the new plan a name.' }));
      fields.name.focus();
      return;
    }
    // A new plan never replaces one of the same name; an opened one is saved only over the
    // version it was read at.
    const condition = open.version === null ? { 'If-None-Match': '*' } : { 'If-Match': `"${open.version}"` };
    try {
      const stored = await api(planPath(name, `?description=${encodeURIComponent(fields.description.value.trim())}`), {
        method: 'PUT', token: token(), body: fields.rules.value,
        headers: { 'Content-Type': 'text/csv', ...condition },
      });
      open = null;
      await openPlan(stored.name, messageBox('ok', 'Saved ', el('strong', {}, el('bdi', {}, stored.name)), ': ',
        `${stored.rules.length} ${stored.rules.length === 1 ? 'rule' : 'rules'}, fallback bin `,
        el('strong', {}, el('bdi', {}, stored.fallback_bin)), '.'));
      await listPlans();
    } catch (error) {
      if (error.status !== 412) {
        show($('plan-msg'), problemBox(error));
        return;
      }
      if (open.version === null) {
        show($('plan-msg'), problemBox(error, {
          hint: 'A plan of this name exists already: open it from the list, or give this one another name.' }));
        return;
      }
      // Someone saved the plan after it was opened here: nothing was written. The text typed is
      // kept so that the change can be made again on the saved plan.
      const reload = el('button', { type: 'button', class: 'secondary', id: 'plan-reload' }, `Open the saved ${name}`);
      reload.addEventListener('click', () => { open = null; openPlan(name); });
      show($('plan-msg'), problemBox(error, {
        hint: 'Someone saved this plan after you opened it, so yours was not saved. Your text is still here: copy your change, open the saved plan and make it again.' }),
      el('div', { class: 'actions' }, reload));
    }
  }

  function askToDelete() {
    show($('plan-msg'));
    if (needToken($('plan-msg'))) return;
    const { name, version } = open;
    const confirm = el('button', { type: 'button', class: 'danger', id: 'plan-delete-yes' }, `Delete ${name}`);
    const close = () => { show($('plan-confirm')); $('plan-delete').focus(); };
    const cancel = el('button', { type: 'button', class: 'secondary', onclick: close }, 'Cancel');
    confirm.addEventListener('click', () => busy(confirm, async () => {
      try {
        const deleted = await api(planPath(name), { method: 'DELETE', token: token(), headers: { 'If-Match': `"${version}"` } });
        open = null;
        $('plan-form').hidden = true;
        show($('plan-confirm'));
        show($('plans-msg'), deletedBox(deleted));
        await listPlans();
      } catch (error) {
        show($('plan-confirm'));
        show($('plan-msg'), problemBox(error, error.status === 412
          ? { hint: 'Someone saved this plan after you opened it, so it was not deleted. Open it again to see what is saved.' } : {}));
      }
    }));
    const onkeydown = (event) => {
      if (event.key === 'Escape' && !confirm.hasAttribute('aria-busy')) {
        event.preventDefault();
        close();
      }
    };
    show($('plan-confirm'), el('div', { class: 'alert alert-info', role: 'alertdialog', 'aria-label': 'Confirm deleting', onkeydown },
      el('p', {}, 'Delete the plan ', el('bdi', {}, name),
        '? Labels, scans and routes that name it will be refused until a plan of that name is saved again.'),
      el('div', { class: 'actions' }, confirm, cancel)));
    confirm.focus();
  }

  // The server answers a delete with the plan as it was; put back as JSON it is restored whole,
  // unless a plan of that name was made in between.
  function deletedBox(deleted) {
    const undo = el('button', { type: 'button', class: 'secondary', id: 'plan-undo' }, 'Undo');
    undo.addEventListener('click', () => busy(undo, async () => {
      try {
        await api(planPath(deleted.name), { method: 'PUT', token: token(), json: deleted, headers: { 'If-None-Match': '*' } });
        show($('plans-msg'), messageBox('ok', 'Restored ', el('strong', {}, el('bdi', {}, deleted.name)), '.'));
        await listPlans();
      } catch (error) {
        show($('plans-msg'), problemBox(error));
      }
    }));
    return messageBox('ok', el('p', {}, 'Deleted ', el('strong', {}, el('bdi', {}, deleted.name)), '.'),
      el('div', { class: 'actions' }, undo));
  }

  async function route() {
    const pin = asciiDigits(fields.pincode.value.trim());
    if (!isPincode(pin)) {
      show($('plan-route-msg'), problemBox({ title: 'Not a pincode',
        message: `“${pin}” is not a pincode: a pincode is six digits, the first 1–9.` }));
      return;
    }
    try {
      const answer = await api(`/api/v1/route/${pin}?plan=${encodeURIComponent(open.name)}`);
      const why = answer.fallback ? ' (no rule matches: the fallback bin)' : ` (the rule for ${answer.matched_prefix})`;
      show($('plan-route-msg'), messageBox('ok', `${pin} goes to bin `, el('strong', { id: 'plan-route-bin' }, el('bdi', {}, answer.bin)), why,
        dirty() ? '. Your unsaved changes are not in this answer.' : '.'));
    } catch (error) {
      show($('plan-route-msg'), problemBox(error));
    }
  }
  $('plan-new').addEventListener('click', () => askToOpen(null, newPlan));
  $('plan-form').addEventListener('submit', (event) => {
    event.preventDefault();
    busy($('plan-save'), save);
  });
  $('plan-delete').addEventListener('click', askToDelete);
  $('plan-close').addEventListener('click', () => askToOpen(null, () => {
    open = null;
    $('plan-form').hidden = true;
    listPlans();
  }));
  $('plan-route').addEventListener('click', () => busy($('plan-route'), route));
  fields.pincode.addEventListener('keydown', (event) => {
    if (event.key === 'Enter') {
      event.preventDefault();
      busy($('plan-route'), route);
    }
  });
  // Leaving the page with unsaved changes asks first, as closing an editor does.
  window.addEventListener('beforeunload', (event) => {
    if (dirty()) event.preventDefault();
  });

  listPlans();
}
