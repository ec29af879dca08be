// API tokens on the registry page: a token made in the page signs in to the same server with its
// role, a revoked one is refused, and the last admin token is kept.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { newPage, screenshot, serverAndBrowser } from './harness.js';

const session = serverAndBrowser();

// The status the server gives `secret` on an admin-only route: 200 admin, 403 another role,
// 401 not a token (or a revoked one).
async function statusWith(secret) {
  const response = await fetch(`${session.server.url}/api/v1/tokens`, { headers: { Authorization: `Bearer ${secret}` } });
  return response.status;
}

async function openRegistry() {
  const page = await newPage(session.browser);
  await page.goto(`${session.server.url}/registry.html`);
  return page;
}

test('a token made in the page works with its role, and a revoked one is refused', async () => {
  const page = await openRegistry();
  // Without the admin token nothing is asked of the server.
  await page.getByRole('button', { name: 'Show tokens' }).click();
  await page.locator('#tokens-msg').filter({ hasText: 'Paste an admin token above first' }).waitFor();
  await page.locator('#token').fill(session.server.adminToken);

  await page.locator('#t-role').selectOption('scanner');
  await page.locator('#t-label').fill('handheld 7');
  await page.getByRole('button', { name: 'Create token' }).click();
  const secretField = page.locator('#token-secret');
  await secretField.waitFor();
  const scanner = await secretField.inputValue();
  assert.match(scanner, /^pt_\d+_/);
  assert.equal(await statusWith(scanner), 403, 'a scanner token: valid, not an admin');
  assert.match(await page.locator('#token-created').textContent(), /\(scanner, handheld 7\).*shown only now/);

  await page.getByRole('button', { name: 'Show tokens' }).click();
  const id = scanner.match(/^pt_(\d+)_/)[1];
  const row = page.locator(`#tokens-body tr[data-token="${id}"]`);
  await row.waitFor();
  assert.match(await row.textContent(), /scanner\s*handheld 7.*active/);
  // The page's own admin token is marked as such.
  assert.match(await page.locator('#tokens-body tr[data-token="1"]').textContent(), /this page’s/);
  // Done hides the secret (a screenshot of the list must not carry one).
  await page.getByRole('button', { name: 'Done: hide the secret' }).click();
  assert.equal(await page.locator('#token-secret').count(), 0);
  await screenshot(page, 'registry-tokens');

  // Escape keeps it, and so does Enter (the question opens on Cancel: a revoke cannot be
  // undone); Revoke revokes it, and the server refuses it from then on.
  await page.getByRole('button', { name: `Revoke token ${id}`, exact: true }).click();
  await page.locator('#token-revoke-yes').press('Escape');
  assert.equal(await statusWith(scanner), 403);
  await page.getByRole('button', { name: `Revoke token ${id}`, exact: true }).click();
  await page.getByRole('alertdialog').waitFor();
  await page.keyboard.press('Enter');
  await page.getByRole('alertdialog').waitFor({ state: 'detached' });
  assert.equal(await statusWith(scanner), 403);
  await page.getByRole('button', { name: `Revoke token ${id}`, exact: true }).click();
  await page.locator('#token-revoke-yes').click();
  await page.locator('#tokens-msg').filter({ hasText: `Token ${id} is revoked.` }).waitFor();
  assert.equal(await statusWith(scanner), 401);
  // Revoked tokens are listed only when asked for, and offer nothing to do.
  await row.waitFor({ state: 'detached' });
  await page.getByLabel('Show revoked tokens').check();
  await row.filter({ hasText: 'revoked' }).waitFor();
  assert.equal(await row.getByRole('button').count(), 0);
  assert.deepEqual(page.problems, []);
});

test('Forget takes the token list and a new secret off the page', async () => {
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Show tokens' }).click();
  await page.locator('#tokens-list').waitFor();
  await page.locator('#t-role').selectOption('counter');
  await page.getByRole('button', { name: 'Create token' }).click();
  await page.locator('#token-secret').waitFor();
  await page.getByRole('button', { name: 'Forget' }).click();
  assert.equal(await page.locator('#token-secret').count(), 0);
  assert.ok(await page.locator('#tokens-list').isHidden());
  assert.equal(await page.locator('#tokens-body').textContent(), '');
  assert.deepEqual(page.problems, []);
});

test('the token list is searched by label, role and id, and says when nothing matches', async () => {
  // A hub has a token per handheld: made through the API, as a script enrolling devices would.
  const made = {};
  for (const [role, label] of [['scanner', 'Handheld dock A'], ['scanner', 'handheld dock B'],
    ['counter', 'Counter 4'], ['scanner', 'Belt camera']]) {
    const response = await fetch(`${session.server.url}/api/v1/tokens`, {
      method: 'POST',
      headers: { Authorization: `Bearer ${session.server.adminToken}`, 'Content-Type': 'application/json' },
      body: JSON.stringify({ role, label }),
    });
    assert.equal(response.status, 201);
    made[label] = (await response.json()).id;
  }
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Show tokens' }).click();
  await page.locator(`#tokens-body tr[data-token="${made['Belt camera']}"]`).waitFor();
  const shownIds = async () => (await page.locator('#tokens-body tr[data-token]').evaluateAll(
    (rows) => rows.map((row) => Number(row.dataset.token)))).sort((a, b) => a - b);
  const search = page.getByLabel('Find a token');

  await search.fill('HANDHELD');  // any case
  assert.deepEqual(await shownIds(), [made['Handheld dock A'], made['handheld dock B']]);
  assert.match(await page.locator('#tokens-caption').textContent(), /2 of \d+ shown match the search/);
  await search.fill('scanner dock b');  // every word, in role or label
  assert.deepEqual(await shownIds(), [made['handheld dock B']]);
  await search.fill(`counter ${made['Counter 4']}`);  // the id too
  assert.deepEqual(await shownIds(), [made['Counter 4']]);
  await search.fill('forklift');
  assert.deepEqual(await shownIds(), []);
  assert.match(await page.locator('#tokens-body').textContent(), /No active token matches “forklift”/);
  await screenshot(page, 'registry-tokens-search');
  await search.fill('');
  assert.ok((await shownIds()).length >= 5);
  assert.doesNotMatch(await page.locator('#tokens-caption').textContent(), /match the search/);

  // Forget takes the search with the list.
  await search.fill('belt');
  await page.getByRole('button', { name: 'Forget' }).click();
  assert.ok(await page.locator('#tokens-find-row').isHidden());
  assert.equal(await search.inputValue(), '');
  assert.deepEqual(page.problems, []);
});

test('on a phone a new token\'s secret is shown whole, broken between characters', async () => {
  const page = await newPage(session.browser, { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(`${session.server.url}/registry.html`);
  await page.locator('#token').fill(session.server.adminToken);
  await page.locator('#t-role').selectOption('scanner');
  await page.getByRole('button', { name: 'Create token' }).click();
  const secret = page.locator('#token-secret');
  await secret.waitFor();
  // Every line of it in the box: it wrapped to three lines in a box of two, the first half hidden.
  // (At this width breaking anywhere alone keeps it to two lines; the box's height is set from
  // the text as well, for narrower screens and larger fonts.)
  const [scroll, client] = await secret.evaluate((box) => [box.scrollHeight, box.clientHeight]);
  assert.ok(scroll <= client, `secret box ${client} px tall for ${scroll} px of text`);
  assert.equal(await secret.evaluate((box) => getComputedStyle(box).wordBreak), 'break-all');
  await screenshot(page, 'registry-token-secret-phone');
  await page.getByRole('button', { name: 'Done: hide the secret' }).click();
  assert.deepEqual(page.problems, []);
});

test('the last admin token is not revoked, and a second one made in the page can revoke the first', async () => {
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Show tokens' }).click();
  await page.locator('#tokens-body tr[data-token="1"]').waitFor();
  await page.getByRole('button', { name: 'Revoke token 1', exact: true }).click();
  assert.match(await page.getByRole('alertdialog').textContent(), /the token this page uses/);
  await page.locator('#token-revoke-yes').click();
  await page.locator('#tokens-msg').filter({ hasText: 'HTTP 409' }).waitFor();
  assert.equal(await statusWith(session.server.adminToken), 200);

  await page.locator('#t-role').selectOption('admin');
  await page.locator('#t-label').fill('second admin');
  await page.getByRole('button', { name: 'Create token' }).click();
  await page.locator('#token-secret').waitFor();
  const second = await page.locator('#token-secret').inputValue();
  assert.equal(await statusWith(second), 200);
  // Signed in with the second, the page revokes the first; which token is the page's follows
  // the field, not the list as it was drawn.
  await page.locator('#token').fill(second);
  const secondId = second.match(/^pt_(\d+)_/)[1];
  await page.getByRole('button', { name: `Revoke token ${secondId}`, exact: true }).click();
  assert.match(await page.getByRole('alertdialog').textContent(), /the token this page uses/);
  await page.getByRole('button', { name: 'Cancel' }).click();
  await page.getByRole('button', { name: 'Revoke token 1', exact: true }).click();
  assert.doesNotMatch(await page.getByRole('alertdialog').textContent(), /the token this page uses/);
  await page.locator('#token-revoke-yes').click();
  await page.locator('#tokens-msg').filter({ hasText: 'Token 1 is revoked.' }).waitFor();
  assert.equal(await statusWith(session.server.adminToken), 401);
  assert.equal(await statusWith(second), 200);
  assert.deepEqual(page.problems, []);
});
