// Dispatch counter: pincodes in, office and district to confirm, label preview, PDF out.
import {
  api, ApiError, query, el, show, problemBox, messageBox, badge, busy, downloadBlob, parsePincodes, bindToken, keepPlan,
  remember, remembered, isWholeToken,
} from './api.js';

const $ = (id) => document.getElementById(id);

const token = bindToken({
  name: 'counter', input: $('token'), status: $('token-status'), forget: $('token-forget'), toggle: $('token-toggle'),
  // The preview was fetched with the token: it goes with it.
  onForget: () => {
    ++batchRun;
    clearPreview('Paste a counter token above to preview and print labels.');
  },
});

const kPreviewDpi = 120;
const kConcurrency = 6;

/** Rows of the table, in the order typed: {text, valid, record, error, include, office}; `office`
 * is the office chosen for the label, null for the record's own. */
let rows = [];
/** The pincode whose label is shown, and its row (a pincode typed twice has two). */
let selected = null;
let selectedRow = -1;
let previewUrl = null;
let previewRequest = 0;
/** Only the latest lookup's answer is drawn; `lookupStop` stops the requests of the one running. */
let lookupRequest = 0;
let lookupStop = null;
/** Settles once the plan list has come and the kept plan is chosen (at the end of this file). */
let plansLoaded = Promise.resolve();
/** A Forget or a new lookup ends a split batch between its parts (the batch's click numbers it). */
let batchRun = 0;

const sizeValue = () => document.querySelector('input[name="size"]:checked').value;
const planValue = () => $('plan').value;
const sizeText = { '100x150mm': '100 × 150 mm', a6: 'A6', '4x6in': '4 × 6 in' };

function labelQuery(extra = {}) {
  return query({ size: sizeValue(), plan: planValue(), ...extra });
}

// `progress(done, total)` is told after each answer: a long list (a thousand pincodes take seconds)
// shows how far it has come.
async function lookupAll(pins, signal, progress = () => {}) {
  const answers = new Map();
  const queue = [...pins];
  const worker = async () => {
    while (queue.length && !signal.aborted) {
      const pin = queue.shift();
      try {
        answers.set(pin, { record: await api(`/api/v1/pincodes/${pin}`, { signal }) });
      } catch (error) {
        answers.set(pin, { error });
      }
      if (!signal.aborted) progress(answers.size, pins.length);
    }
  };
  await Promise.all(Array.from({ length: Math.min(kConcurrency, pins.length) }, worker));
  return answers;
}

function printable() {
  return rows.filter((r) => r.include && r.record && r.record.status === 'active');
}

// A button stays disabled while its request runs (aria-busy), whatever the rows do meanwhile.
function updateButtons() {
  const count = printable().length;
  const batch = $('batch-pdf');
  batch.disabled = count === 0 || batch.hasAttribute('aria-busy');
  batch.textContent = count === 1 ? 'Batch PDF (1 label)' : `Batch PDF (${count} labels)`;
  const ok = selected !== null;
  for (const id of ['download-pdf', 'print-pdf']) $(id).disabled = !ok || $(id).hasAttribute('aria-busy');
}

/** busy() for the print buttons: when the request ends, each button follows the rows again. */
function printing(button, work) {
  return busy(button, work).finally(updateButtons);
}

// Only the registry's own 404 says a pincode does not exist; a server that could not be asked
// (down, busy) says nothing about it.
function notFound(row) {
  return Boolean(row.error) && row.error.status === 404;
}

function renderTable() {
  const body = $('results-body');
  const found = rows.filter((r) => r.record).length;
  $('results-caption').textContent =
    `${rows.length} ${rows.length === 1 ? 'pincode' : 'pincodes'}, ${found} found. Tick the ones to print.`;
  const copies = new Map();
  for (const row of rows) copies.set(row.text, (copies.get(row.text) || 0) + 1);
  show(body, rows.map((row, index) => {
    const pin = row.text;
    // A pincode listed twice gets two rows; their controls are told apart by row number.
    const which = copies.get(pin) > 1 ? `${pin} (row ${index + 1})` : pin;
    if (!row.record) {
      const why = !row.valid
        ? 'Not a pincode: six digits, the first 1–9.'
        : (row.error && (row.error.detail || row.error.title)) || 'Not found.';
      return el('tr', { class: 'is-error' },
        el('td', {}, el('input', { type: 'checkbox', disabled: true, 'aria-label': `${which} cannot be printed` })),
        el('td', { class: 'mono' }, pin),
        el('td', {}, badge('error', !row.valid ? 'invalid' : notFound(row) ? 'not found' : 'not checked'), ' ', why));
    }
    const r = row.record;
    const retired = r.status !== 'active';
    const place = placeOf(row);
    const check = el('input', {
      type: 'checkbox', checked: row.include && !retired, disabled: retired, 'aria-label': `Print a label for ${which}`,
      onchange: (event) => { row.include = event.target.checked; row.edited = true; updateButtons(); },
    });
    const previewButton = el('button', {
      type: 'button', class: 'link', 'aria-label': `Preview the label for ${which}`, disabled: retired,
      onclick: () => select(index).then(() => revealPreview(index)),
    }, 'Preview');
    // Preview goes under the pincode, and the district and state under the office, rather than
    // in columns of their own: the table then fits its card at every width, Preview in view, and
    // the office's name has the room left.
    return el('tr', { 'data-pincode': pin, 'data-row': index },
      el('td', {}, check),
      el('td', { class: 'pin' }, el('span', { class: 'mono nowrap' }, pin),
        el('div', {}, retired ? el('span', { class: 'small muted' }, 'No new labels') : previewButton)),
      el('td', { class: 'office' }, officeCell(row, index, which, retired), retired ? [' ', badge(r.status)] : null,
        // Isolated: an Urdu district and state ran together right to left, the state first.
        el('div', { class: 'place small' },
          el('bdi', { class: 'district' }, place.district), ', ', el('bdi', { class: 'state' }, place.state))));
  }));
  $('results').hidden = rows.length === 0;
  markSelected();
  updateButtons();
}

async function lookup() {
  // A list submitted while another is still being looked up (Ctrl+Enter submits whatever the
  // button's state) replaces it: the older lookup stops asking and its answers are dropped.
  const request = ++lookupRequest;
  ++batchRun;  // a batch of the list before stops between its parts
  if (lookupStop) lookupStop.abort();
  const stop = new AbortController();
  lookupStop = stop;
  const parsed = parsePincodes($('pins').value);
  show($('lookup-msg'));
  show($('print-msg'));  // news of the last list's labels would read as news of this one's
  if (parsed.length === 0) {
    // The table goes with the list it showed: its Batch PDF would print pincodes no longer listed.
    lookupStop = null;
    rows = [];
    selected = null;
    selectedRow = -1;
    renderTable();
    clearPreview('Look up a pincode to see its label here.');
    show($('lookup-msg'), messageBox('info', 'Type or paste at least one pincode, e.g. 110001.'));
    $('pins').focus();
    return;
  }
  const unique = [...new Set(parsed.filter((p) => p.valid).map((p) => p.text))];
  // Said only for a list long enough to take a while to look up.
  const kProgressFrom = 50;
  const answers = await lookupAll(unique, stop.signal, (done, total) => {
    if (total >= kProgressFrom && request === lookupRequest) {
      show($('lookup-msg'), messageBox('info', `Looking up ${done} of ${total} pincodes…`));
    }
  });
  if (request !== lookupRequest) return;
  lookupStop = null;
  show($('lookup-msg'));
  // A pincode already in the table keeps the clerk's choices: a list looked up again (one
  // pincode added) printed every row with its record's office, ticked, without a word.
  const kept = new Map(copies(rows).map((id, i) => [id, rows[i]]));
  const wasSelected = selectedRow >= 0 ? copies(rows)[selectedRow] : null;
  const ids = copies(parsed);
  rows = parsed.map((p, i) => {
    const before = kept.get(ids[i]);
    const answer = answers.get(p.text) || {};
    // A server that could not be asked (down, busy) says nothing new about a pincode: a row it had
    // answered stays as it was, choices and all. It went "not checked", and the next lookup then
    // ticked it again with its record's office, so a batch printed labels the clerk had changed.
    if (answer.error && ![400, 404].includes(answer.error.status) && before && before.record) {
      return { ...before, ...p };
    }
    const row = { ...p, ...answer, include: true, office: null };
    if (before && before.record && before.record.status === 'active' && row.record && row.record.status === 'active') {
      row.include = before.include;
      row.edited = before.edited;
      if (before.office && (row.record.offices || []).some((o) => o.name === before.office)) row.office = before.office;
    }
    return row;
  });
  // A failure that is not about the pincode itself (server down, busy) is worth saying once.
  const general = [...answers.values()].find((a) => a.error && ![400, 404].includes(a.error.status));
  if (general) show($('lookup-msg'), problemBox(general.error));
  // Forget the old selection before drawing, or the new table marks a row nobody picked.
  selected = null;
  selectedRow = -1;
  renderTable();
  // The label shown stays, when its row is still listed and printable; else the first printable.
  const printableAt = (i) => i >= 0 && rows[i].record && rows[i].record.status === 'active';
  const again = wasSelected ? ids.indexOf(wasSelected) : -1;
  const first = printableAt(again) ? again : rows.findIndex((r, i) => printableAt(i));
  if (first >= 0) await select(first);
  else {
    clearPreview('No printable pincode in the list.');
    updateButtons();
  }
}

// Each row named by its pincode and which copy of it the row is: "110001#2" is the second row of
// 110001, so a pincode listed twice keeps each row's choices.
function copies(list) {
  const seen = new Map();
  return list.map(({ text }) => {
    const n = (seen.get(text) || 0) + 1;
    seen.set(text, n);
    return `${text}#${n}`;
  });
}

function clearPreview(text) {
  ++previewRequest; // a preview still on its way must not replace this text
  $('preview').removeAttribute('aria-busy');
  if (previewUrl) URL.revokeObjectURL(previewUrl);
  previewUrl = null;
  show($('preview'), el('p', { class: 'placeholder' }, text));
}

// Marks the row whose label is shown (none when nothing is selected).
function markSelected() {
  for (const tr of $('results-body').rows) {
    const chosen = Number(tr.dataset.row) === selectedRow;
    tr.classList.toggle('is-selected', chosen);
    if (chosen) tr.setAttribute('aria-current', 'true');
    else tr.removeAttribute('aria-current');
  }
}

async function select(index) {
  selectedRow = index;
  selected = rows[index].text;
  markSelected();
  updateButtons();
  await refreshPreview();
}

// On a phone the preview is below the whole table: bring it into view when a row's Preview is
// tapped, or the tap looks as if it did nothing. Not when another row was picked meanwhile.
// Once the picture is decoded: before, it has no height, and the card scrolled to grew past the
// screen's bottom.
async function revealPreview(index) {
  const picture = $('label-preview');
  if (picture) await picture.decode().catch(() => {});
  if (index !== selectedRow) return;
  $('preview').closest('section').scrollIntoView({ block: 'nearest' });
}

// The district and state the label prints: the chosen office's (a pincode's offices can lie in
// several districts), else the record's own. A retired row prints nothing and shows its record's
// office, so its record's place too.
function placeOf(row) {
  const r = row.record;
  const chosen = row.office && r.status === 'active' ? (r.offices || []).find((o) => o.name === row.office) : null;
  return chosen ? { district: chosen.district, state: chosen.state } : { district: r.district, state: r.state };
}

// The office the label prints: a pincode with several offers them all, the record's own first.
function officeCell(row, index, which, retired) {
  const r = row.record;
  const names = (r.offices || []).map((o) => o.name);
  if (retired || names.length < 2) return r.office || '—';
  const ordered = [r.office, ...names.filter((n) => n !== r.office)];
  return el('select', {
    class: 'office-choice', 'aria-label': `Office printed on the label for ${which}`,
    title: row.office || r.office, // a narrow column cuts long names; hovering shows it whole
    onchange: (event) => {
      event.target.title = event.target.value;
      row.office = event.target.value === r.office ? null : event.target.value;
      row.edited = true;
      const tr = event.target.closest('tr');
      const place = placeOf(row);
      tr.querySelector('.district').textContent = place.district;
      tr.querySelector('.state').textContent = place.state;
      if (index === selectedRow) refreshPreview();
    },
  }, ordered.map((name) => el('option', { value: name, selected: name === (row.office || r.office) ? true : null }, name)));
}

async function refreshPreview() {
  if (!selected) return;
  const row = rows[selectedRow];
  if (!token()) {
    clearPreview('Paste a counter token above to preview and print labels.');
    return;
  }
  const request = ++previewRequest;
  $('preview').setAttribute('aria-busy', 'true');
  // The label shown until the new one comes is another row's, size's or plan's: dimmed, and its
  // caption says which is coming, so that nobody prints what the picture shows by mistake.
  const caption = $('preview').querySelector('figcaption');
  if (caption) caption.textContent = `Loading the label for ${selected}…`;
  try {
    await plansLoaded;
    const blob = await api(`/api/v1/labels/${selected}.png${labelQuery({ dpi: kPreviewDpi, office: row.office })}`,
      { token: token(), as: 'blob' });
    if (request !== previewRequest) return;
    if (previewUrl) URL.revokeObjectURL(previewUrl);
    previewUrl = URL.createObjectURL(blob);
    const office = row.office || (row.record ? row.record.office : '');
    // The office's and plan's names are isolated: an Urdu office turned the size after it round
    // ("150 × 100", "mm" at the far end).
    const parts = [selected, office ? el('bdi', {}, office) : null, sizeText[sizeValue()] || sizeValue(),
      ['plan ', el('bdi', {}, planValue() || 'default')]].filter(Boolean);
    show($('preview'),
      el('img', { id: 'label-preview', src: previewUrl, alt: `Label for ${selected}${office ? ` (${office})` : ''}` }),
      el('figcaption', { class: 'small muted space-above-md' }, parts.map((part, i) => (i ? [' · ', part] : part))));
  } catch (error) {
    if (request !== previewRequest) return;
    if (previewUrl) URL.revokeObjectURL(previewUrl);
    previewUrl = null;
    show($('preview'), problemBox(error));
    // Retired since it was looked up: its rows are marked so, as a refused batch marks them.
    if (error.status === 410) markRetired(selected);
  } finally {
    if (request === previewRequest) $('preview').removeAttribute('aria-busy');
  }
}

// The pincode is taken when the request starts: the clerk may pick another row before it ends.
async function labelPdf(pincode, office) {
  await plansLoaded;
  return api(`/api/v1/labels/${pincode}.pdf${labelQuery({ office })}`, { token: token(), as: 'blob' });
}

// The server names a refused batch item by its place in the list sent ("pincodes[2]: …"), which
// leaves out the rows not printed; the clerk sees the table's row numbers. Returns the row sent
// and the detail naming it ("row 5: …"), or null when the problem is not about one item.
function refusedItem(error, sent) {
  if (!(error instanceof ApiError) || !error.detail) return null;
  const match = /^pincodes\[(\d+)\](?:\.\w+)?(?=:)/.exec(error.detail);
  const row = match ? sent[Number(match[1])] : undefined;
  if (!row) return null;
  const rest = error.detail.slice(match[0].length);
  const number = rows.indexOf(row);
  // A lookup since may have replaced the table; the detail names the pincode itself.
  return { row, detail: number >= 0 ? `row ${number + 1}${rest}` : rest.replace(/^:\s*/, '') };
}

// A pincode the server says is retired (410) since it was looked up: every row of it is shown
// retired and left out of the batch; its label, when shown, goes.
function markRetired(pincode) {
  for (const row of rows) {
    if (row.text === pincode && row.record) {
      row.record = { ...row.record, status: 'retired' };
      row.include = false;
      row.office = null;  // its row shows the record's office (officeCell), and its place
    }
  }
  if (selected === pincode) {
    selected = null;
    selectedRow = -1;
    clearPreview(`${pincode} is retired: no new labels are issued for it.`);
  }
  renderTable();
}

function needToken() {
  if (token()) return false;
  show($('print-msg'), messageBox('info', 'Paste a counter token above first.'));
  $('token').focus();
  return true;
}

$('lookup-form').addEventListener('submit', (event) => {
  event.preventDefault();
  busy($('lookup'), lookup);
});
$('pins').addEventListener('keydown', (event) => {
  if (event.key === 'Enter' && (event.ctrlKey || event.metaKey)) {
    event.preventDefault();
    $('lookup-form').requestSubmit();
  }
});

$('download-pdf').addEventListener('click', (event) => printing(event.currentTarget, async () => {
  if (needToken() || selected === null) return;
  const pincode = selected;
  show($('print-msg'));
  try {
    downloadBlob(await labelPdf(pincode, rows[selectedRow].office), `label-${pincode}.pdf`);
    show($('print-msg'), messageBox('ok', `Label for ${pincode} downloaded (label-${pincode}.pdf).`));
  } catch (error) {
    show($('print-msg'), problemBox(error));
    if (error.status === 410) markRetired(pincode);
  }
}));

$('print-pdf').addEventListener('click', (event) => {
  if (needToken() || selected === null) return;
  const pincode = selected;
  const office = rows[selectedRow].office;
  // Opened before the request so that pop-up blockers see a click; filled in when the PDF arrives.
  const win = window.open('', '_blank');
  printing(event.currentTarget, async () => {
    show($('print-msg'));
    try {
      const blob = await labelPdf(pincode, office);
      if (!win) {
        // Blocked: navigating this page to the PDF would lose the clerk's list, so save it instead.
        downloadBlob(blob, `label-${pincode}.pdf`);
        show($('print-msg'), messageBox('info',
          `The browser blocked the new tab, so the label for ${pincode} was downloaded (label-${pincode}.pdf): print it at 100 % (actual size).`));
        return;
      }
      const url = URL.createObjectURL(blob);
      win.location.href = url;
      // Released when the tab closes, not before: the PDF viewer's reload and download read the
      // URL again, and a clerk may print minutes later. Kept for good, it would hold every printed
      // PDF until this page reloads.
      const watch = setInterval(() => {
        if (win.closed) {
          clearInterval(watch);
          URL.revokeObjectURL(url);
        }
      }, 5_000);
      show($('print-msg'), messageBox('ok', `The label for ${pincode} opened in a new tab: print it from there at 100 % (actual size).`));
    } catch (error) {
      if (win) win.close();
      show($('print-msg'), problemBox(error));
      if (error.status === 410) markRetired(pincode);
    }
  });
});

// A batch over the server's limit (its 413 gives the limit as `max_batch`) is made as several
// PDFs of at most that many labels, in the list's order: a clerk with 120 labels got a refusal and
// had to untick 20 rows one by one. Every part is asked with the size, plan and token of the
// click; when a later part fails, the rows of the parts saved are unticked, so that the next click
// asks only for the rest. Each PDF is named by its first pincode and count (and its part), so that one
// batch's files do not replace another's in the downloads folder.
$('batch-pdf').addEventListener('click', (event) => printing(event.currentTarget, async () => {
  if (needToken()) return;
  await plansLoaded;  // the kept plan, not the default it replaces
  const run = ++batchRun;
  const chosen = printable();
  const asked = { size: sizeValue(), plan: planValue(), token: token() };
  show($('print-msg'));
  const saved = [];
  const savedRows = [];
  let perPdf = chosen.length;
  let part = chosen;
  try {
    for (let start = 0; start < chosen.length;) {
      if (run !== batchRun) return;  // forgotten or replaced before this part was asked for
      part = chosen.slice(start, start + perPdf);
      const body = { pincodes: part.map((r) => (r.office ? { pincode: r.text, office: r.office } : r.text)), size: asked.size };
      if (asked.plan) body.plan = asked.plan;
      let blob;
      try {
        blob = await api('/api/v1/labels', { method: 'POST', token: asked.token, json: body, as: 'blob' });
      } catch (error) {
        const limit = error instanceof ApiError && error.status === 413 ? error.numbers.max_batch : undefined;
        if (Number.isInteger(limit) && limit > 0 && limit < part.length) {
          perPdf = limit;
          continue;
        }
        throw error;
      }
      if (run !== batchRun) return;  // forgotten or replaced meanwhile: nothing more is saved
      const parts = Math.ceil(chosen.length / perPdf);
      const name = `labels-${part[0].text}-${part.length}${parts > 1 ? `-part${saved.length + 1}of${parts}` : ''}.pdf`;
      downloadBlob(blob, name);
      saved.push(name);
      savedRows.push(...part);
      start += part.length;
    }
    show($('print-msg'), messageBox('ok', saved.length === 1
      ? `${chosen.length} ${chosen.length === 1 ? 'label' : 'labels'} in one PDF downloaded (${saved[0]}).`
      : `${chosen.length} labels downloaded in ${saved.length} PDFs of at most ${perPdf} each, the most the server makes per PDF: ${saved.join(', ')}. If the browser asked whether this page may download several files, it needs your yes.`));
  } catch (error) {
    if (run !== batchRun) return;
    if (savedRows.length) {
      // Part of the batch is saved: its rows are unticked, so that the next click asks for the rest.
      for (const row of savedRows) row.include = false;
      renderTable();
    }
    const refused = refusedItem(error, part);
    const already = saved.length ? ` Already downloaded, and unticked: ${saved.join(', ')}.` : '';
    const tooMany = error instanceof ApiError && error.status === 413;
    show($('print-msg'), problemBox(refused ? new ApiError(error.status, error.title, refused.detail + already)
      : already ? new ApiError(error.status, error.title, `${error.detail || error.message}${already}`) : error,
    tooMany ? { hint: 'Untick some labels and download this batch, then tick the rest for a second one.' } : {}));
    if (refused && error.status === 410) markRetired(refused.row.text);
  }
}));

// A counter keeps its label size (the stock in its printer) and plan from one visit to the next.
const keptSize = document.querySelector(`input[name="size"][value="${CSS.escape(remembered('counter.size') || '')}"]`);
if (keptSize) keptSize.checked = true;
for (const input of document.querySelectorAll('input[name="size"]')) {
  input.addEventListener('change', () => {
    remember('counter.size', sizeValue());
    refreshPreview();
  });
}
$('plan').addEventListener('change', refreshPreview);
$('token').addEventListener('change', refreshPreview);
// A whole token pasted shows the label at once, not when the field loses focus.
$('token').addEventListener('input', () => {
  if (isWholeToken(token())) refreshPreview();
});

// Leaving or reloading the page asks first while the table holds choices the clerk made (an office
// picked, a row ticked or unticked by hand): they are not kept, and the list looked up again would
// print the defaults. Rows the page unticked itself (retired, a batch part saved) ask nothing.
window.addEventListener('beforeunload', (event) => {
  if (rows.some((row) => row.edited && row.record && row.record.status === 'active')) event.preventDefault();
});

// Previews and prints wait for the kept plan (plansLoaded).
plansLoaded = keepPlan($('plan'), 'counter.plan');
updateButtons();
