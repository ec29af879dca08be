// API tokens on the registry page: list them, create one (its secret shown once, here, until
// dismissed), revoke one after a confirmation. Every call takes the admin token of the page's
// admin section; Forget there takes the list and any secret shown with it.
import {
  api, el, show, problemBox, messageBox, busy, confirmBox, serverRole, replicaNote, utcMinute,
} from './api.js';

const $ = (id) => document.getElementById(id);

// A secret is pt_<id>_<random>: the id says which listed token this page itself is using.
function idOfSecret(secret) {
  const match = /^pt_(\d+)_/.exec(secret || '');
  return match ? Number(match[1]) : null;
}

// What a search in the list matches a token by: its id, role and label, in lower case.
function matchText(t) {
  return `${t.id} ${t.role} ${t.label || ''}`.toLowerCase();
}

// The text into the clipboard: the Clipboard API where the page may use it (https, localhost),
// else the browser's copy command on the selected field (a hub's server on plain http).
async function copyText(field, text) {
  field.focus();
  field.select();
  try {
    await navigator.clipboard.writeText(text);
    return true;
  } catch {
    return document.execCommand('copy');
  }
}

/**
 * Sets up the token section. `token()` gives the admin token; `needToken(messageBox)` says one is
 * missing (and returns true) before anything is sent. Returns `forget()`, which takes the list
 * and any secret shown off the page (for the admin section's Forget).
 */
export function setUpTokens({ token, needToken }) {
  let tokens = null;         // the list as last read, or null when none is shown
  let showRevoked = false;
  let readOnlyServer = false;
  let listRequest = 0;       // only the latest list read draws
  let newest = null;         // the id of the token made last, marked in the list

  // The list as read, drawn again when the page's own token (marked) or the filter changes.
  function draw() {
    if (tokens === null) {
      show($('tokens-body'));
      $('tokens-list').hidden = true;
      $('tokens-filter').hidden = true;
      $('tokens-find-row').hidden = true;
      return;
    }
    const mine = idOfSecret(token());
    const words = $('tokens-find').value.toLowerCase().split(/\s+/).filter(Boolean);
    const listed = [...tokens].reverse().filter((t) => showRevoked || !t.revoked_at);
    const rows = listed.filter((t) => words.every((w) => matchText(t).includes(w)));
    show($('tokens-body'), rows.map((t) => el('tr', { 'data-token': t.id, class: t.id === newest ? 'is-selected' : (t.revoked_at ? 'muted' : null) },
      el('td', { class: 'num mono' }, String(t.id)),
      el('td', {}, t.role),
      el('td', { class: 'token-label' }, t.label ? el('bdi', {}, t.label) : '—', t.id === mine ? el('span', { class: 'hint' }, ' (this page’s)') : null),
      el('td', { class: 'hide-narrow nowrap' }, utcMinute(t.created_at)),
      el('td', {}, t.revoked_at ? el('span', { title: `revoked ${t.revoked_at}` }, 'revoked') : 'active'),
      el('td', {}, t.revoked_at || readOnlyServer ? null : el('button', { type: 'button', class: 'link', onclick: () => askToRevoke(t),
        'aria-label': `Revoke token ${t.id}` }, 'Revoke…')))));
    if (words.length > 0 && rows.length === 0) {
      show($('tokens-body'), el('tr', {}, el('td', { colspan: 6, class: 'muted' },
        `No ${showRevoked ? '' : 'active '}token matches “${$('tokens-find').value.trim()}”.`)));
    }
    const active = tokens.filter((t) => !t.revoked_at).length;
    const total = tokens.length === 1 ? '1 token' : `${tokens.length} tokens`;
    const found = words.length > 0 ? `; ${rows.length} of ${listed.length} shown match the search` : '';
    $('tokens-caption').textContent = `${total}, ${active} active, newest first${showRevoked ? '' : '; revoked ones hidden'}` +
      found + (readOnlyServer ? ' (as of this replica’s copy of the registry)' : '');
    $('tokens-list').hidden = false;
    $('tokens-filter').hidden = false;
    $('tokens-find-row').hidden = false;
  }

  async function listTokens() {
    const request = ++listRequest;
    try {
      const answer = await api('/api/v1/tokens', { token: token() });
      if (request !== listRequest) return;
      tokens = answer.tokens;
      draw();
    } catch (error) {
      if (request !== listRequest) return;
      tokens = null;
      draw();
      show($('tokens-msg'), problemBox(error));
    }
  }

  function hideSecret() {
    show($('token-created'));
  }

  function clearConfirm() {
    show($('token-confirm'));
    for (const row of $('tokens-body').querySelectorAll('tr.confirm-row')) row.remove();
  }

  function forget() {
    ++listRequest;
    tokens = null;
    $('tokens-find').value = '';
    newest = null;
    hideSecret();
    clearConfirm();
    show($('tokens-msg'));
    draw();
  }

  function askToRevoke(t) {
    show($('tokens-msg'));
    if (needToken($('tokens-msg'))) return;
    const rowButton = () => $('tokens-body').querySelector(`tr[data-token="${t.id}"] button`);
    const close = () => { clearConfirm(); (rowButton() || $('tokens-show')).focus(); };
    // Whose token the page uses is read now: the field may have changed since the list was drawn.
    const own = idOfSecret(token()) === t.id;
    const { box, noButton } = confirmBox({
      label: 'Confirm revoking',
      message: [`Revoke token ${t.id} (${t.role}`, t.label ? [', ', el('bdi', {}, t.label)] : null,
        ')? Whatever signs in with it is refused from now on. This cannot be undone.',
        own ? ' It is the token this page uses: the page will need another admin token.' : ''],
      yes: `Revoke token ${t.id}`, yesId: 'token-revoke-yes',
      onNo: close,
      onYes: async () => {
        try {
          // The token sent is the field's now, which may have changed since the box opened.
          const ownNow = idOfSecret(token()) === t.id;
          await api(`/api/v1/tokens/${t.id}`, { method: 'DELETE', token: token() });
          clearConfirm();
          if (ownNow) {
            // Nothing more can be listed with it: the list goes, and the page says what to do.
            forget();
            show($('tokens-msg'), messageBox('ok', `Token ${t.id} is revoked. It was this page’s token: paste another admin token above to go on.`));
            $('token').focus();
            return;
          }
          show($('tokens-msg'), messageBox('ok', `Token ${t.id} is revoked.`));
          await listTokens();
          (rowButton() || $('tokens-msg')).focus();
        } catch (error) {
          close();
          show($('tokens-msg'), problemBox(error));
        }
      },
    });
    // Shown under the token's row, not below a list that may be thousands of pixels long.
    const row = $('tokens-body').querySelector(`tr[data-token="${t.id}"]`);
    clearConfirm();
    if (row) row.after(el('tr', { class: 'confirm-row' }, el('td', { colspan: 6 }, box)));
    else show($('token-confirm'), box);
    noButton.focus();  // revoking cannot be undone: a second Enter must not be what revokes
  }

  async function create() {
    show($('tokens-msg'));
    hideSecret();
    if (needToken($('tokens-msg'))) return;
    const role = $('t-role').value;
    const label = $('t-label').value.trim();
    try {
      const made = await api('/api/v1/tokens', { method: 'POST', token: token(), json: label ? { role, label } : { role } });
      // A text area, so a phone shows the whole secret to check by eye; never inside a form, so
      // no browser offers to save it.
      // Broken between any two characters (a break after one of the secret's own hyphens read as
      // a hyphenation), and as tall as the secret needs: on a phone it wrapped to three lines of
      // two.
      const secret = el('textarea', { id: 'token-secret', readonly: true, rows: 2, class: 'mono secret',
        'aria-label': `Secret of token ${made.id}`, spellcheck: 'false', autocomplete: 'off' });
      secret.value = made.secret;
      const copy = el('button', { type: 'button', class: 'secondary' }, 'Copy');
      copy.addEventListener('click', async () => {
        copy.textContent = (await copyText(secret, made.secret)) ? 'Copied' : 'Selected: press Ctrl+C (or long-press) to copy';
      });
      const done = el('button', { type: 'button', id: 'token-secret-done', class: 'secondary' }, 'Done: hide the secret');
      done.addEventListener('click', () => { hideSecret(); $('token-create').focus(); });
      show($('token-created'), messageBox('ok',
        el('p', {}, `Token ${made.id} (${made.role}`, made.label ? [', ', el('bdi', {}, made.label)] : null,
          ') is made. Its secret is shown only now: copy it to the device that will use it, then hide it.'),
        secret, el('div', { class: 'actions' }, copy, done)));
      secret.style.height = 'auto';
      secret.style.height = `${secret.scrollHeight + 2}px`;
      secret.focus();
      secret.select();
      $('t-label').value = '';
      newest = made.id;
      if (tokens !== null) await listTokens();
    } catch (error) {
      show($('tokens-msg'), problemBox(error));
    }
  }

  async function noteReplica() {
    const registry = await serverRole();
    if (registry?.role !== 'replica') return;
    readOnlyServer = true;
    $('token-create-form').hidden = true;
    show($('tokens-replica'), replicaNote('tokens', registry.primary));
    draw();
  }

  $('token-create-form').addEventListener('submit', (event) => {
    event.preventDefault();
    busy($('token-create'), create);
  });
  $('tokens-show').addEventListener('click', () => {
    show($('tokens-msg'));
    if (needToken($('tokens-msg'))) return;
    busy($('tokens-show'), listTokens);
  });
  $('tokens-find').addEventListener('input', draw);
  $('tokens-revoked').addEventListener('change', (event) => {
    showRevoked = event.currentTarget.checked;
    draw();
  });
  // The "this page's" mark follows the token field.
  $('token').addEventListener('input', draw);
  // A secret is not left on a page that is put away (or kept in the back-forward cache).
  window.addEventListener('pagehide', hideSecret);

  noteReplica();
  return forget;
}
