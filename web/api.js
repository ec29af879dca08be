// Shared helpers for the PinTag pages: a fetch wrapper that turns RFC 9457 problem+json answers
// into errors the pages can show, tokens kept in sessionStorage, and small DOM helpers.
// Plain ES module, served as is by `pintag serve --web`.

/** An answer that was not 2xx (or no answer): the problem's title and detail, fit to show. */
export class ApiError extends Error {
  constructor(status, title, detail, numbers = {}) {
    super(detail ? `${title}: ${detail}` : title);
    this.name = 'ApiError';
    this.status = status;
    this.title = title;
    this.detail = detail;
    // The problem's numeric extension members (a 413's max_pixels, say): what a page can act on.
    this.numbers = numbers;
  }
}

// Titles for answers without a problem body (over HTTP/2 statusText is empty): ours, and what a
// proxy in front (docs/SCALING.md) may answer on its own.
const kReasons = {
  400: 'Bad Request', 401: 'Unauthorized', 403: 'Forbidden', 404: 'Not Found', 405: 'Method Not Allowed',
  408: 'Request Timeout', 409: 'Conflict', 410: 'Gone', 413: 'Content Too Large', 415: 'Unsupported Media Type',
  429: 'Too Many Requests', 431: 'Request Header Fields Too Large',
  500: 'Internal Server Error', 502: 'Bad Gateway', 503: 'Service Unavailable', 504: 'Gateway Timeout',
  507: 'Insufficient Storage',
};

async function problemFrom(response) {
  let title = response.statusText || kReasons[response.status] || 'Error';
  let detail = '';
  const numbers = {};
  const type = response.headers.get('Content-Type') || '';
  try {
    if (type.includes('json')) {
      const problem = await response.json();
      if (problem && typeof problem === 'object') {
        if (problem.title) title = String(problem.title);
        if (problem.detail) detail = String(problem.detail);
        for (const [name, value] of Object.entries(problem)) {
          if (name !== 'status' && Number.isFinite(value)) numbers[name] = value;
        }
      }
    } else if (type.includes('text/plain')) {
      detail = (await response.text()).trim().slice(0, 300);
    } else {
      // An HTML error page (a proxy's, a captive portal's) shown as text would be markup.
      detail = 'The answer did not come from PinTag (a proxy or gateway between may have sent it).';
    }
  } catch {
    // An unreadable body: the status line is all there is.
  }
  return new ApiError(response.status, title, detail, numbers);
}

/**
 * Calls the PinTag API.
 *   path    '/api/v1/…' (same origin)
 *   token   bearer secret, sent when given
 *   json    a value sent as application/json
 *   body    a raw body (FormData, Blob, …) when json is not given
 *   as      'json' (default), 'blob' or 'response'
 * Resolves with the parsed answer; rejects with an ApiError carrying the problem's title and detail.
 */
export async function api(path, { method = 'GET', token = '', json, body, headers = {}, as = 'json', signal } = {}) {
  const sent = new Headers(headers);
  if (token) {
    // A header holds Latin-1 only: the browser would throw its own message, naming no field.
    if (!kTokenText.test(token)) {
      throw new ApiError(0, 'Token not valid',
        'The token holds a character a PinTag token cannot have (a token is pt_ followed by letters, digits, - and _). Paste it again.');
    }
    sent.set('Authorization', `Bearer ${token}`);
  }
  if (json !== undefined) {
    sent.set('Content-Type', 'application/json');
    body = JSON.stringify(json);
  }
  if (as === 'json' && !sent.has('Accept')) sent.set('Accept', 'application/json');
  let response;
  try {
    response = await fetch(path, { method, headers: sent, body, signal, cache: 'no-store' });
  } catch (error) {
    if (error && error.name === 'AbortError') throw error;
    throw new ApiError(0, 'Server unreachable', 'The PinTag server did not answer. Check the connection and try again.');
  }
  if (!response.ok) throw await problemFrom(response);
  if (as === 'blob') return response.blob();
  if (as === 'response') return response;
  try {
    return await response.json();
  } catch {
    // A 200 that is not JSON is not PinTag's answer (a login portal, a proxy's page).
    throw new ApiError(response.status, 'Unexpected answer',
      'The answer was not PinTag\'s JSON; a proxy or portal between may have sent it.');
  }
}

/** Query string from an object, leaving out empty values. */
export function query(params) {
  const search = new URLSearchParams();
  for (const [name, value] of Object.entries(params)) {
    if (value !== undefined && value !== null && value !== '') search.set(name, String(value));
  }
  const text = search.toString();
  return text ? `?${text}` : '';
}

// ---------- DOM helpers ----------

/** el('p', {class: 'x'}, 'text', child…): an element; attributes starting with "on" are listeners. */
export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [name, value] of Object.entries(attrs || {})) {
    if (value === undefined || value === null || value === false) continue;
    if (name.startsWith('on') && typeof value === 'function') node.addEventListener(name.slice(2), value);
    else if (name === 'class') node.className = value;
    else if (name === 'text') node.textContent = value;
    else node.setAttribute(name, value === true ? '' : String(value));
  }
  for (const child of children.flat(Infinity)) {
    if (child === undefined || child === null || child === false) continue;
    node.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return node;
}

/** Replaces the content of `container` with `nodes`. */
export function show(container, ...nodes) {
  container.replaceChildren(...nodes.flat(Infinity).filter((n) => n !== null && n !== undefined && n !== false));
}

const kAuthHints = {
  401: 'The token was not accepted: paste a valid token (it starts with pt_) above.',
  403: 'This token is valid but its role may not do this.',
};

const kReplicaHint = 'This server is a read-only copy of the registry: make the change on the primary server named above.';

/** An alert box for an error: the problem's title, HTTP status and detail, plus a hint for auth errors. */
export function problemBox(error, { hint } = {}) {
  // The server's problem, or a check the page makes itself ({ title, message }), names itself.
  const title = error && error.title ? error.title : 'Something went wrong';
  const detail = error instanceof ApiError ? error.detail : String(error && error.message ? error.message : error);
  const status = error instanceof ApiError && error.status ? el('span', { class: 'code' }, `HTTP ${error.status}`) : null;
  // A replica refuses a change before it looks at the token: the role hint would mislead.
  const replica = error instanceof ApiError && error.title === 'Read-Only Replica';
  const extra = hint || (replica ? kReplicaHint : error instanceof ApiError ? kAuthHints[error.status] : '');
  return el('div', { class: 'alert alert-error', role: 'alert' },
    el('strong', { class: 'problem-title' }, title), status,
    detail ? el('p', { class: 'problem-detail' }, detail) : null,
    extra ? el('p', { class: 'small' }, extra) : null);
}

/** An alert box for good news or information. */
export function messageBox(kind, ...content) {
  return el('div', { class: `alert alert-${kind}`, role: kind === 'ok' ? 'status' : null }, ...content);
}

/** A status badge: active, retired, unknown_key, error; `text` replaces the status as its words. */
export function badge(status, text) {
  const words = text || (status === 'unknown_key' ? 'unknown key' : status);
  return el('span', { class: `badge badge-${status}` }, words);
}

// The buttons busy() holds: how many calls hold each one, and whether it was disabled before the
// first of them.
const held = new WeakMap();

/**
 * Marks a button busy while `work` runs; returns what `work` returns. Calls may overlap (a form
 * submitted again by keyboard while its button is busy): the button stays busy until the last
 * one ends and then gets back what it was before the first began, never the busy state itself.
 */
export async function busy(button, work) {
  let hold = held.get(button);
  if (!hold) {
    hold = { count: 0, was: button.disabled };
    held.set(button, hold);
  }
  ++hold.count;
  button.disabled = true;
  button.setAttribute('aria-busy', 'true');
  try {
    return await work();
  } finally {
    if (--hold.count === 0) {
      held.delete(button);
      button.disabled = hold.was;
      button.removeAttribute('aria-busy');
    }
  }
}

let roleAnswer = null;

/** The server's part in replication ({role, primary, …} of /api/v1/registry), asked once a page; null when unknown. */
export function serverRole() {
  roleAnswer ??= api('/api/v1/registry').catch(() => null);
  return roleAnswer;
}

/** What a read-only replica says about `what` (plans, tokens): read here, changed on its primary. */
export function replicaNote(what, primary) {
  return messageBox('info', `This server is a read-only copy of the registry: ${what} are read here and changed on the primary`,
    primary ? [' (', el('a', { href: `${primary.replace(/\/$/, '')}/registry.html` }, primary), ')'] : '', '.');
}

let confirmCount = 0;

/**
 * A confirmation asked in the page (an alertdialog, not window.confirm, which a screen reader and
 * a test harness handle worse): `message` and two buttons. Yes runs `onYes` with its button busy;
 * No, and Escape while yes is not running, run `onNo`. Returns the box and its two buttons: the
 * caller shows the box and focuses one (No, when yes cannot be undone: a second Enter of the one
 * that opened the box must not confirm it).
 */
export function confirmBox({ label, message, yes, yesId, yesClass = 'danger', no = 'Cancel', onYes, onNo }) {
  const yesButton = el('button', { type: 'button', class: yesClass, id: yesId }, yes);
  const noButton = el('button', { type: 'button', class: 'secondary', onclick: onNo }, no);
  yesButton.addEventListener('click', () => busy(yesButton, onYes));
  const text = el('p', { id: `confirm-text-${++confirmCount}` }, message);
  const onkeydown = (event) => {
    if (event.key === 'Escape' && !yesButton.hasAttribute('aria-busy')) {
      event.preventDefault();
      onNo();
    }
  };
  // Described by its text, so that a screen reader says what is asked, not only the label.
  const box = el('div', { class: 'alert alert-info', role: 'alertdialog', 'aria-label': label,
    'aria-describedby': text.id, onkeydown }, text, el('div', { class: 'actions' }, yesButton, noButton));
  return { box, yesButton, noButton };
}

/** Saves a blob under a file name, as a download. */
export function downloadBlob(blob, filename) {
  const url = URL.createObjectURL(blob);
  const link = el('a', { href: url, download: filename, hidden: true });
  document.body.append(link);
  link.click();
  link.remove();
  setTimeout(() => URL.revokeObjectURL(url), 60_000);
}

// ---------- pincodes ----------

/** Six digits, the first 1–9: what the server accepts as a pincode. */
export function isPincode(text) {
  return /^[1-9][0-9]{5}$/.test(text);
}

// The zero of each run of ten decimal digits an Indian clerk's keyboard may type: Arabic-Indic,
// Urdu's extended Arabic-Indic, Devanagari, Bengali, Gurmukhi, Gujarati, Oriya, Tamil, Telugu,
// Kannada, Malayalam, and fullwidth (a CJK input method).
const kDigitZeros = [0x0660, 0x06f0, 0x0966, 0x09e6, 0x0a66, 0x0ae6, 0x0b66, 0x0be6, 0x0c66, 0x0ce6,
  0x0d66, 0xff10];

/** `text` with those digits written as 0–9: "११०००१" is 110001. Other characters are kept. */
export function asciiDigits(text) {
  return text.replace(/\p{Nd}/gu, (digit) => {
    const code = digit.codePointAt(0);
    const zero = kDigitZeros.find((z) => code >= z && code <= z + 9);
    return zero === undefined ? digit : String(code - zero);
  });
}

/**
 * The pincodes in pasted text: separated by spaces, commas, semicolons or new lines; "110 001"
 * (three and three digits) is read as one. Any Unicode space (a no-break space from a web page or
 * spreadsheet) counts as a space, and zero-width characters (U+200B, a byte order mark, …) are
 * dropped, since the clerk cannot see them; digits of Indian scripts are read as 0–9
 * (asciiDigits). Returns [{text, valid}] in order, duplicates kept.
 */
export function parsePincodes(text) {
  const visible = asciiDigits(text).replace(/[\u00ad\u180e\u200b-\u200d\u2060\ufeff]/g, '');
  const joined = visible.replace(/(^|[^0-9])([0-9]{3})\p{Zs}([0-9]{3})(?![0-9])/gu, '$1$2$3');
  return joined.split(/[\s,;]+/u).filter(Boolean).map((item) => ({ text: item, valid: isPincode(item) }));
}

/**
 * A pincode typed or pasted into a field of its own, read as parsePincodes reads one: "110 001",
 * as a label prints it, is 110001. The text as typed (trimmed, its digits as 0–9) when it holds
 * more or less than one, so that a refusal quotes it.
 */
export function pincodeFieldValue(text) {
  const items = parsePincodes(text);
  return items.length === 1 ? items[0].text : asciiDigits(text.trim());
}

/** A server time (ISO 8601 in UTC, "2026-12-07T19:56:50.862Z") as pages show one: "2026-12-07 19:56 UTC". */
export function utcMinute(iso) {
  return `${iso.slice(0, 16).replace('T', ' ')} UTC`;
}

// ---------- tokens ----------

const kStorePrefix = 'pintag.token.';

// What a token may hold as sent: printable ASCII without spaces. The server judges the rest.
const kTokenText = /^[\x21-\x7e]+$/;

/**
 * A pasted token as it is meant: spaces, line breaks and invisible characters (a zero-width space,
 * a byte order mark or a bidi mark that came along from a chat or a PDF) dropped, since a token
 * holds none.
 */
export function cleanToken(text) {
  return text.replace(/[\s\u00ad\u061c\u180e\u200b-\u200f\u202a-\u202e\u2060-\u2069\ufeff]/gu, '');
}

/**
 * Whether `token` (cleaned) is a whole secret: pt_<id>_ and 43 characters (32 random bytes,
 * base64url). A page acts on a token as it is pasted only then, so that typing one does not send it
 * unfinished.
 */
export function isWholeToken(token) {
  return /^pt_\d+_[A-Za-z0-9_-]{43}$/.test(token);
}

function store() {
  try {
    return window.sessionStorage;
  } catch {
    return null;  // storage blocked: the token lives in the field only
  }
}

/** The token saved for `name` in this tab ('' when none). */
export function savedToken(name) {
  const s = store();
  return (s && s.getItem(kStorePrefix + name)) || '';
}

/**
 * Wires a token field: filled from sessionStorage, saved on every change (this tab only), a
 * Show/Hide toggle and a Forget button (`onForget` then runs too: a page clears what it fetched
 * with the token). Returns a function giving the current token, cleaned (cleanToken).
 */
export function bindToken({ name, input, status, forget, toggle, onForget }) {
  const s = store();
  input.value = savedToken(name);
  const describe = () => {
    if (!status) return;
    status.textContent = cleanToken(input.value)
      ? 'Token kept for this browser tab only; it is forgotten when the tab closes.'
      : 'No token yet. Paste one to continue.';
  };
  input.addEventListener('input', () => {
    const value = cleanToken(input.value);
    if (s) {
      if (value) s.setItem(kStorePrefix + name, value);
      else s.removeItem(kStorePrefix + name);
    }
    describe();
  });
  if (forget) {
    forget.addEventListener('click', () => {
      input.value = '';
      if (s) s.removeItem(kStorePrefix + name);
      describe();
      if (onForget) onForget();
      input.focus();
    });
  }
  if (toggle) {
    toggle.addEventListener('click', () => {
      const hidden = input.type === 'password';
      input.type = hidden ? 'text' : 'password';
      toggle.textContent = hidden ? 'Hide' : 'Show';
      toggle.setAttribute('aria-pressed', String(hidden));
    });
  }
  describe();
  return () => cleanToken(input.value);
}

// A station's settings (the hub's sort plan, the label stock in the printer) kept from one visit
// to the next in localStorage under `pintag.<key>`; null when none is kept or storage is off.
export function remembered(key) {
  try {
    return window.localStorage.getItem(`pintag.${key}`);
  } catch {
    return null;
  }
}

export function remember(key, value) {
  try {
    if (value === null) window.localStorage.removeItem(`pintag.${key}`);
    else window.localStorage.setItem(`pintag.${key}`, value);
  } catch {
    // Storage off (a private window's quota): the setting lasts this visit only.
  }
}

/**
 * Keeps a <select>'s choice under `key` (remember above): the kept choice is restored now when the
 * select has it, and every change is kept. For a plan list filled later, use keepPlan.
 */
export function rememberSelect(select, key) {
  const kept = remembered(key);
  if (kept !== null && [...select.options].some((o) => o.value === kept)) select.value = kept;
  select.addEventListener('change', () => {
    select.dataset.chosen = '1';
    remember(key, select.value);
  });
}

/**
 * Fills a plan <select> from the server. It then shows the plan chosen on this page since it
 * opened, else `preferred` (a kept choice) when the server has it, else the default plan (a kept
 * plan since deleted must not leave the list on whichever plan came first).
 */
async function loadPlans(select, preferred = 'default') {
  try {
    const { plans } = await api('/api/v1/sortplans');
    const current = select.value;
    // An option holds text only, no <bdi>: a name or description written right to left is
    // isolated with FSI … PDI, so it does not take the dash and the other part into its order.
    const isolated = (text) => `\u2068${text}\u2069`;
    for (const plan of plans) {
      let text = isolated(plan.name);
      if (plan.description) text += ` — ${isolated(plan.description.length > 44 ? `${plan.description.slice(0, 43)}…` : plan.description)}`;
      const known = [...select.options].find((o) => o.value === plan.name);
      if (known) {
        // An option the page starts with (the default plan): give it its description too.
        known.textContent = text;
        if (plan.description) known.title = plan.description;
      } else {
        select.append(el('option', { value: plan.name, title: plan.description || null }, text));
      }
    }
    const has = (name) => [...select.options].some((o) => o.value === name);
    const want = select.dataset.chosen ? current : preferred;
    if (has(want)) select.value = want;
    else if (!select.dataset.chosen && has('default')) select.value = 'default';
  } catch {
    // Plans are a convenience here; the default plan still works when the list fails.
  }
}

/**
 * A plan <select> whose choice is kept under `key` (rememberSelect) and filled from the server
 * (loadPlans) with the kept plan chosen; a kept plan the server no longer has is forgotten. The
 * promise settles once the list has come: what a page makes with the plan waits for it, or it
 * would be made with the default plan the kept one replaces.
 */
export function keepPlan(select, key) {
  rememberSelect(select, key);
  const kept = remembered(key);
  return loadPlans(select, kept || 'default').then(() => {
    if (kept && select.value !== kept && !select.dataset.chosen) remember(key, null);
  });
}
