// Sort plans on the registry page: list them, open one as CSV text, save it back (conditionally,
// so one admin's save never undoes another's), create, delete with an undo, and route a pincode
// by the plan as saved. The server checks every plan; the page shows its problem as it says it.
import {
  api, el, show, problemBox, messageBox, busy, isPincode, pincodeFieldValue, confirmBox, downloadBlob, serverRole,
  replicaNote,
} from './api.js';

const $ = (id) => document.getElementById(id);

const kNewPlanText = 'prefix,bin\n*,manual\n';
const kMaxNameBytes = 64;          // the server's limits (docs/API.md), checked here so that a long
const kMaxDescriptionBytes = 200;  // name or description is not a "414 URI Too Long"
// Characters a plan name may not hold: a URL would have to encode them, and some not even then.
const kRefusedNameCharacters = /[/?#%\\+&=]/;

function planPath(name, params = '') {
  return `/api/v1/sortplans/${encodeURIComponent(name)}${params}`;
}

// The version digits of a plan's JSON ETag ("<hex>").
function versionOf(etag) {
  return (etag || '').replace(/^"|"$/g, '');
}

// A plan as the CSV the server reads (docs/API.md): the header, the * row for the fallback, then
// a row per rule. Written here from the JSON, so that one read gives the text, the description
// and the version together. A field holding a comma, a quote or a line break is quoted; the
// server refuses fields that start or end with a space, so none needs quoting for that.
function csvField(text) {
  return /[",\r\n]/.test(text) ? `"${text.replaceAll('"', '""')}"` : text;
}
function planCsv(plan) {
  const rows = [['prefix', 'bin'], ['*', plan.fallback_bin], ...plan.rules.map((r) => [r.prefix, r.bin])];
  return rows.map((row) => row.map(csvField).join(',')).join('\n') + '\n';
}

function utf8Bytes(text) {
  return new TextEncoder().encode(text).length;
}

/**
 * Sets up the sort plan section. `token()` gives the admin token; `needToken(messageBox)` says
 * one is missing (and returns true) before anything is sent.
 */
export function setUpSortPlans({ token, needToken }) {
  // The plan in the editor: its name as stored, the version it was read at (null for a new plan)
  // and its text and description as read, to tell whether the fields hold unsaved changes. Set
  // only once a read or save succeeded: a failed one leaves the editor as it was.
  let open = null;
  let readOnlyServer = false;  // a replica: plans are read here, changed on the primary
  // A save on its way: the editor is not closed, deleted or replaced under it, since its answer
  // fills the editor when it comes.
  let saving = false;

  const fields = { name: $('p-name'), description: $('p-description'), rules: $('p-rules'), pincode: $('p-try') };
  const dirty = () => open !== null &&
    (fields.rules.value !== open.text || fields.description.value !== open.description ||
      (open.version === null && fields.name.value.trim() !== ''));
  // A message about what was just done, where it was done: the editor's when it is shown.
  const editorShown = () => !$('plan-form').hidden;
  const say = (...nodes) => show(editorShown() ? $('plan-msg') : $('plans-msg'), ...nodes);

  let listFailed = false;
  async function listPlans() {
    try {
      const { plans } = await api('/api/v1/sortplans');
      show($('plans-body'), plans.map((plan) => el('tr', {},
        el('td', { class: 'plan-name' }, el('button', { type: 'button', class: 'link', onclick: () => askToOpen(() => openPlan(plan.name)),
          'aria-label': `Open plan ${plan.name}`, 'data-plan': plan.name }, el('bdi', {}, plan.name))),
        el('td', {}, el('bdi', {}, plan.fallback_bin)),
        el('td', { class: 'num' }, String(plan.rules)),
        el('td', { class: 'hide-narrow' }, plan.description ? el('bdi', {}, plan.description) : '—'))));
      markSelected();
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

  function markSelected() {
    for (const button of $('plans-body').querySelectorAll('button[data-plan]')) {
      button.closest('tr').classList.toggle('is-selected', open?.version != null && button.dataset.plan === open.name);
    }
  }

  // The editor shows `state` ({name, version, text, description}).
  function showEditor(state) {
    open = state;
    const saved = state.version !== null;
    $('plan-form').hidden = false;
    show($('plan-edit-h'), saved ? ['Plan ', el('bdi', {}, state.name)] : 'New plan');
    fields.name.value = state.name;
    fields.name.readOnly = saved;
    fields.description.value = state.description;
    fields.rules.value = state.text;
    $('plan-csv').hidden = !saved;
    if (saved) {
      $('plan-csv').href = planPath(state.name, '?format=csv');
      $('plan-csv').setAttribute('download', `${state.name}.csv`);
    }
    // The default plan serves every label and scan that names none: the server never deletes it.
    $('plan-delete').hidden = readOnlyServer || !saved || state.name === 'default';
    $('plan-try').hidden = !saved;
    show($('plan-confirm'));
    show($('plan-route-msg'));
    markSelected();
  }

  function stateOf(plan, etag) {
    return { name: plan.name, version: versionOf(etag), text: planCsv(plan), description: plan.description || '' };
  }

  // One read: the JSON holds the rules, the description and (in its ETag) the version together.
  async function openPlan(name, note) {
    try {
      const response = await api(planPath(name), { as: 'response' });
      showEditor(stateOf(await response.json(), response.headers.get('ETag')));
      show($('plan-msg'), note || null);
      $('plan-form').scrollIntoView({ block: 'nearest' });
      $('plan-edit-h').focus();
    } catch (error) {
      say(problemBox(error));
      if (error.status === 404) listPlans();
    }
  }

  // Opening another plan, or closing, over unsaved changes would drop them: asked first.
  function askToOpen(then) {
    show($('plan-confirm'));
    if (saving) {
      show($('plan-msg'), messageBox('info', 'The plan is being saved: wait for the save, then open another.'));
      return;
    }
    if (!dirty()) {
      then();
      return;
    }
    const keep = () => { show($('plan-confirm')); fields.rules.focus(); };
    const { box, noButton } = confirmBox({
      label: 'Unsaved changes',
      message: ['The plan being edited (', open.name ? el('bdi', {}, open.name) : 'new', ') has unsaved changes.'],
      yes: 'Discard my changes', yesId: 'plan-discard', no: 'Keep editing',
      onNo: keep,
      onYes: async () => { show($('plan-confirm')); await then(); },
    });
    show($('plan-confirm'), box);
    noButton.focus();  // discarded edits cannot be had back: Enter keeps them
  }

  function newPlan() {
    showEditor({ name: '', version: null, text: kNewPlanText, description: '' });
    show($('plan-msg'));
    fields.name.focus();
  }

  function closeEditor() {
    const name = open?.name;
    open = null;
    $('plan-form').hidden = true;
    show($('plan-msg'));
    markSelected();
    const row = [...$('plans-body').querySelectorAll('button[data-plan]')].find((b) => b.dataset.plan === name);
    (row || $('plan-new')).focus();
  }

  // What the page can tell before sending: a new name's characters, and the two lengths.
  function nameRefusal(name) {
    if (!name) return { title: 'No name', message: 'Give the new plan a name.' };
    if (name === '.' || name === '..' || kRefusedNameCharacters.test(name)) {
      return { title: 'Name not usable',
        message: 'A plan name cannot be . or .. or hold / ? # % \\ + & or =: a web address would have to encode them.' };
    }
    if (utf8Bytes(name) > kMaxNameBytes) {
      return { title: 'Name too long', message: `A plan name is at most ${kMaxNameBytes} bytes (this one is ${utf8Bytes(name)}).` };
    }
    return null;
  }
  function descriptionRefusal(description) {
    if (utf8Bytes(description) > kMaxDescriptionBytes) {
      return { title: 'Description too long',
        message: `A description is at most ${kMaxDescriptionBytes} bytes (this one is ${utf8Bytes(description)}).` };
    }
    return null;
  }

  function downloadMine() {
    const name = open.name || fields.name.value.trim() || 'plan';
    downloadBlob(new Blob([fields.rules.value], { type: 'text/csv' }), `${name}-mine.csv`);
  }

  // After a 412: the plan changed or went away since it was opened. Nothing was written; the
  // text typed stays, and the admin chooses what to do with it.
  async function explainConflict(error, name) {
    let current = null;
    try {
      current = await api(planPath(name), { as: 'response' });
    } catch (readError) {
      if (readError.status !== 404) {
        show($('plan-msg'), problemBox(error));
        return;
      }
    }
    const keepText = el('button', { type: 'button', class: 'secondary', onclick: downloadMine }, 'Download my text');
    if (current === null) {
      const asNew = el('button', { type: 'button', id: 'plan-save-as-new' }, 'Save it as a new plan');
      asNew.addEventListener('click', () => {
        // A new plan of the same name, holding what was typed (still unsaved, so still guarded).
        const typed = { rules: fields.rules.value, description: fields.description.value };
        showEditor({ name, version: null, text: '', description: '' });
        fields.rules.value = typed.rules;
        fields.description.value = typed.description;
        busy($('plan-save'), save);
      });
      show($('plan-msg'), problemBox(error, {
        hint: 'Someone deleted this plan after you opened it, so yours was not saved. Your text is still here.' }),
      el('div', { class: 'actions' }, asNew, keepText));
      asNew.focus();
      return;
    }
    const plan = await current.json();
    const etag = current.headers.get('ETag');
    const reload = el('button', { type: 'button', class: 'secondary', id: 'plan-reload' },
      'Discard my text and open the saved ', el('bdi', {}, name));
    reload.addEventListener('click', () => { showEditor(stateOf(plan, etag)); show($('plan-msg')); fields.rules.focus(); });
    show($('plan-msg'), problemBox(error, {
      hint: 'Someone saved this plan after you opened it, so yours was not saved. Your text is still here: download it or copy your change, then open the saved plan and make it again.' }),
    el('div', { class: 'actions' }, reload, keepText));
    reload.focus();
  }

  async function save() {
    show($('plan-msg'));
    show($('plan-confirm'));
    if (needToken($('plan-msg'))) return;
    const creating = open.version === null;
    const name = creating ? fields.name.value.trim() : open.name;
    const description = fields.description.value.trim();
    const text = fields.rules.value;
    // An opened plan keeps its stored name, even one from before these checks.
    const wrongName = creating ? nameRefusal(name) : null;
    const wrong = wrongName || descriptionRefusal(description);
    if (wrong) {
      show($('plan-msg'), problemBox(wrong));
      (wrongName ? fields.name : fields.description).focus();
      return;
    }
    // A new plan never replaces one of the same name; an opened one is saved only over the
    // version it was read at.
    const condition = creating ? { 'If-None-Match': '*' } : { 'If-Match': `"${open.version}"` };
    // The fields are held while the plan is on its way: the stored plan is shown when it comes
    // back, and what was typed meanwhile would be lost; nor is the editor closed, deleted or
    // replaced under it.
    const hold = (held) => {
      $('plan-fields').disabled = held;
      saving = held;
      $('plan-delete').disabled = held;
      $('plan-close').disabled = held;
    };
    hold(true);
    try {
      const response = await api(planPath(name, `?description=${encodeURIComponent(description)}`), {
        method: 'PUT', token: token(), body: text, as: 'response',
        headers: { 'Content-Type': 'text/csv', Accept: 'application/json', ...condition },
      });
      const stored = await response.json();
      showEditor(stateOf(stored, response.headers.get('ETag')));
      hold(false);  // the list read below only marks the plan's row
      show($('plan-msg'), messageBox('ok', 'Saved ', el('strong', {}, el('bdi', {}, stored.name)), ': ',
        `${stored.rules.length} ${stored.rules.length === 1 ? 'rule' : 'rules'}, fallback bin `,
        el('strong', {}, el('bdi', {}, stored.fallback_bin)), '.'));
      await listPlans();
    } catch (error) {
      if (error.status === 412 && creating) {
        show($('plan-msg'), problemBox(error, {
          hint: 'A plan of this name exists already: open it from the list, or give this one another name.' }));
      } else if (error.status === 412) {
        await explainConflict(error, name);
      } else {
        show($('plan-msg'), problemBox(error));
      }
      // Someone else's save or delete is why: the list shows the plans as they are now (it said
      // the old rule count beside the conflict).
      if (error.status === 412) await listPlans();
    } finally {
      hold(false);
    }
  }

  function askToDelete() {
    show($('plan-msg'));
    if (needToken($('plan-msg'))) return;
    const { name, version } = open;
    const close = () => { show($('plan-confirm')); $('plan-delete').focus(); };
    const { box, yesButton } = confirmBox({
      label: 'Confirm deleting',
      message: ['Delete the plan ', el('bdi', {}, name),
        '? Labels, scans and routes that name it will be refused until a plan of that name is saved again.',
        dirty() ? ' Your unsaved changes to it go too.' : ''],
      yes: ['Delete ', el('bdi', {}, name)], yesId: 'plan-delete-yes',
      onNo: close,
      onYes: async () => {
        try {
          const deleted = await api(planPath(name), { method: 'DELETE', token: token(), headers: { 'If-Match': `"${version}"` } });
          open = null;
          $('plan-form').hidden = true;
          show($('plan-confirm'));
          const { box: note, undo } = deletedBox(deleted);
          show($('plans-msg'), note);
          await listPlans();
          undo.focus();
        } catch (error) {
          close();
          show($('plan-msg'), problemBox(error, error.status === 412
            ? { hint: 'Someone saved this plan after you opened it, so it was not deleted. Open it again to see what is saved.' } : {}));
          if (error.status === 412) await listPlans();
        }
      },
    });
    show($('plan-confirm'), box);
    yesButton.focus();
  }

  // The server answers a delete with the plan as it was; put back it is restored whole (its
  // version is a hash of what it holds), unless a plan of that name was made in between. Put
  // back as CSV: as JSON a plan over about 83,000 rules is more than the server reads.
  function deletedBox(deleted) {
    const undo = el('button', { type: 'button', class: 'secondary', id: 'plan-undo' }, 'Undo');
    undo.addEventListener('click', () => busy(undo, async () => {
      try {
        await api(planPath(deleted.name, `?description=${encodeURIComponent(deleted.description || '')}`), {
          method: 'PUT', token: token(), body: planCsv(deleted),
          headers: { 'Content-Type': 'text/csv', 'If-None-Match': '*' },
        });
        show($('plans-msg'), messageBox('ok', 'Restored ', el('strong', {}, el('bdi', {}, deleted.name)), '.'));
        await listPlans();
        $('plans-msg').focus();
      } catch (error) {
        show($('plans-msg'), problemBox(error));
      }
    }));
    const box = messageBox('ok', el('p', {}, 'Deleted ', el('strong', {}, el('bdi', {}, deleted.name)), '.'),
      el('div', { class: 'actions' }, undo));
    return { box, undo };
  }

  async function route() {
    const pin = pincodeFieldValue(fields.pincode.value);
    if (!isPincode(pin)) {
      show($('plan-route-msg'), problemBox({ title: 'Not a pincode',
        message: `“${pin}” is not a pincode: a pincode is six digits, the first 1–9.` }));
      return;
    }
    try {
      const answer = await api(`/api/v1/route/${pin}?plan=${encodeURIComponent(open.name)}`);
      const why = answer.fallback ? ' (no rule matches: the fallback bin)' : ` (the rule for ${answer.matched_prefix})`;
      // A pincode the registry does not hold (a typo, say) is routed all the same: said, or the
      // admin checking one reads a confident bin for a parcel no label can be made for.
      const status = answer.status === 'unknown'
        ? ` ${pin} is not in the registry: no label is made for it.`
        : answer.status === 'retired' ? ` ${pin} is retired: no new labels are made for it.` : '';
      show($('plan-route-msg'), messageBox(answer.status === 'unknown' ? 'info' : 'ok', `${pin} goes to bin `,
        el('strong', { id: 'plan-route-bin' }, el('bdi', {}, answer.bin)), why,
        dirty() ? '. Your unsaved changes are not in this answer.' : '.', status));
    } catch (error) {
      show($('plan-route-msg'), problemBox(error));
    }
  }

  // A read-only replica refuses every change: said once, and the buttons that would ask for one
  // are not offered.
  async function noteReplica() {
    const registry = await serverRole();
    if (registry?.role !== 'replica') return;
    readOnlyServer = true;
    $('plan-new').hidden = true;
    $('plan-save').hidden = true;
    $('plan-delete').hidden = true;
    show($('plans-replica'), replicaNote('plans', registry.primary));
  }

  $('plan-new').addEventListener('click', () => askToOpen(newPlan));
  $('plan-form').addEventListener('submit', (event) => {
    event.preventDefault();
    // Focus lost to the held fields comes back to Save; a button offered after a conflict, or the
    // token field asked for, keeps it.
    busy($('plan-save'), save).then(() => {
      if (document.activeElement === document.body || document.activeElement === null) $('plan-save').focus();
    });
  });
  $('plan-delete').addEventListener('click', askToDelete);
  $('plan-close').addEventListener('click', () => askToOpen(closeEditor));
  $('plan-route').addEventListener('click', () => busy($('plan-route'), route));
  fields.pincode.addEventListener('keydown', (event) => {
    if (event.key === 'Enter') {
      event.preventDefault();
      busy($('plan-route'), route);
    }
  });
  // Leaving the page with unsaved changes asks first, as closing the editor does.
  window.addEventListener('beforeunload', (event) => {
    if (dirty()) event.preventDefault();
  });

  listPlans();
  noteReplica();
}
