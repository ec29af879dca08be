// API tokens on the registry page: list them, create one (its secret shown once, here), revoke
// one after a confirmation. Every call takes the admin token of the page's admin section.
import { api, el, show, problemBox, messageBox, busy, confirmBox } from './api.js';

const $ = (id) => document.getElementById(id);

// A secret is pt_<id>_<random>: the id says which listed token this page itself is using.
function idOfSecret(secret) {
  const match = /^pt_(\d+)_/.exec(secret || '');
  return match ? Number(match[1]) : null;
}

/**
 * Sets up the token section. `token()` gives the admin token; `needToken(messageBox)` says one is
 * missing (and returns true) before anything is sent.
 */
export function setUpTokens({ token, needToken }) {
  let shown = false;  // the list is drawn: drawn again after each change

  async function listTokens() {
    try {
      const { tokens } = await api('/api/v1/tokens', { token: token() });
      const mine = idOfSecret(token());
      show($('tokens-body'), tokens.map((t) => el('tr', { class: t.revoked_at ? 'muted' : null, 'data-token': t.id },
        el('td', { class: 'num mono' }, String(t.id)),
        el('td', {}, t.role),
        el('td', {}, t.label ? el('bdi', {}, t.label) : '—', t.id === mine ? el('span', { class: 'hint' }, ' (this page’s)') : null),
        el('td', { class: 'hide-narrow nowrap' }, t.created_at),
        el('td', {}, t.revoked_at ? `revoked ${t.revoked_at}` : 'active'),
        el('td', {}, t.revoked_at ? null : el('button', { type: 'button', class: 'link', onclick: () => askToRevoke(t, mine),
          'aria-label': `Revoke token ${t.id}` }, 'Revoke…')))));
      const active = tokens.filter((t) => !t.revoked_at).length;
      $('tokens-caption').textContent = `${tokens.length} tokens, ${active} active`;
      $('tokens-list').hidden = false;
      shown = true;
    } catch (error) {
      $('tokens-list').hidden = true;
      shown = false;
      show($('tokens-msg'), problemBox(error));
    }
  }

  function askToRevoke(t, mine) {
    show($('tokens-msg'));
    const row = () => $('tokens-body').querySelector(`tr[data-token="${t.id}"] button`);
    const close = () => { show($('token-confirm')); (row() || $('tokens-show')).focus(); };
    const { box, yesButton } = confirmBox({
      label: 'Confirm revoking',
      message: [`Revoke token ${t.id} (${t.role}`, t.label ? [', ', el('bdi', {}, t.label)] : null,
        ')? Whatever signs in with it is refused from now on. This cannot be undone.',
        t.id === mine ? ' It is the token this page uses: the page will need another admin token.' : ''],
      yes: `Revoke token ${t.id}`, yesId: 'token-revoke-yes',
      onNo: close,
      onYes: async () => {
        try {
          await api(`/api/v1/tokens/${t.id}`, { method: 'DELETE', token: token() });
          show($('token-confirm'));
          show($('tokens-msg'), messageBox('ok', `Token ${t.id} is revoked.`));
          // The page's own token, revoked, can list nothing more.
          if (t.id === mine) {
            $('tokens-list').hidden = true;
          } else {
            await listTokens();
          }
          $('tokens-msg').focus();
        } catch (error) {
          close();
          show($('tokens-msg'), problemBox(error));
        }
      },
    });
    show($('token-confirm'), box);
    box.scrollIntoView({ block: 'nearest' });
    yesButton.focus();
  }

  async function create() {
    show($('tokens-msg'));
    show($('token-created'));
    if (needToken($('tokens-msg'))) return;
    const role = $('t-role').value;
    const label = $('t-label').value.trim();
    try {
      const made = await api('/api/v1/tokens', { method: 'POST', token: token(), json: label ? { role, label } : { role } });
      const secret = el('input', { type: 'text', id: 'token-secret', readonly: true, value: made.secret,
        class: 'mono', 'aria-label': `Secret of token ${made.id}`, spellcheck: 'false' });
      const copy = el('button', { type: 'button', class: 'secondary' }, 'Copy');
      copy.addEventListener('click', async () => {
        secret.select();
        try {
          await navigator.clipboard.writeText(made.secret);
          copy.textContent = 'Copied';
        } catch {
          // No clipboard here (a page not served over https, say): the text is selected to copy.
          copy.textContent = 'Selected: copy it';
        }
      });
      show($('token-created'), messageBox('ok',
        el('p', {}, `Token ${made.id} (${made.role}`, made.label ? [', ', el('bdi', {}, made.label)] : null,
          ') is made. Its secret is shown only now: copy it to the device that will use it.'),
        el('div', { class: 'row' }, el('div', { class: 'grow' }, secret), copy)));
      secret.focus();
      secret.select();
      $('t-label').value = '';
      if (shown) await listTokens();
    } catch (error) {
      show($('tokens-msg'), problemBox(error));
    }
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
}
