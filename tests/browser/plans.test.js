// Sort plans on the registry page: listed, created, saved over the version read (and refused
// over another's save), refused with the server's reason, routed by, deleted and restored. Every
// effect is checked through the API of the same server, not only on the page.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { newPage, screenshot, serverAndBrowser } from './harness.js';

const session = serverAndBrowser();

async function apiJson(path, options = {}) {
  const response = await fetch(`${session.server.url}${path}`, options);
  return { status: response.status, etag: response.headers.get('ETag'), body: await response.json() };
}

// A textarea's text is its value, which locator filters do not see.
function valueHolds(page, selector, text) {
  return page.waitForFunction(([sel, wanted]) => document.querySelector(sel).value.includes(wanted), [selector, text]);
}

async function openRegistry() {
  const page = await newPage(session.browser);
  await page.goto(`${session.server.url}/registry.html`);
  await page.locator('#plans-caption').filter({ hasText: /^\d+ plans?$/ }).waitFor();
  return page;
}

test('the seeded plan is listed and opens as its CSV; the default plan has no Delete', async () => {
  const page = await openRegistry();
  const seeded = await apiJson('/api/v1/sortplans/default');
  const row = page.locator('#plans-body tr', { hasText: 'default' });
  assert.match(await row.textContent(), new RegExp(`default\\s*${seeded.body.fallback_bin}\\s*${seeded.body.rules.length}`));
  await page.getByRole('button', { name: 'Open plan default' }).click();
  await page.locator('#plan-edit-h').filter({ hasText: 'Plan default' }).waitFor();
  const text = await page.locator('#p-rules').inputValue();
  const csv = await (await fetch(`${session.server.url}/api/v1/sortplans/default?format=csv`)).text();
  assert.equal(text, csv);
  assert.equal(await page.locator('#p-description').inputValue(), seeded.body.description);
  assert.ok(await page.locator('#p-name').evaluate((input) => input.readOnly));
  assert.ok(await page.locator('#plan-delete').isHidden());
  // Routed by the plan as saved, as the server routes it.
  const routed = await apiJson('/api/v1/route/560001?plan=default');
  await page.locator('#p-try').fill('560001');
  await page.getByRole('button', { name: 'Route', exact: true }).click();
  await page.locator('#plan-route-bin').filter({ hasText: routed.body.bin }).waitFor();
  assert.match(await page.locator('#plan-route-msg').textContent(), new RegExp(`the rule for ${routed.body.matched_prefix}`));
  assert.deepEqual(page.problems, []);
});

test('a new plan is saved, refused with the line named when wrong, and routes pincodes', async () => {
  const page = await openRegistry();
  await page.getByRole('button', { name: 'New plan' }).click();
  await page.locator('#p-name').fill('hub-north');
  await page.locator('#p-description').fill('two bins for the north');
  await page.locator('#p-rules').fill('prefix,bin\n*,floor\n11,delhi\n110001,parliament\n');
  // Without a token nothing is sent.
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'Paste an admin token above first' }).waitFor();
  assert.equal((await apiJson('/api/v1/sortplans/hub-north')).status, 404);

  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'Saved hub-north: 2 rules, fallback bin floor.' }).waitFor();
  const stored = await apiJson('/api/v1/sortplans/hub-north');
  assert.equal(stored.status, 200);
  assert.equal(stored.body.description, 'two bins for the north');
  assert.equal(stored.body.fallback_bin, 'floor');
  assert.deepEqual(stored.body.rules, [{ prefix: '11', bin: 'delhi' }, { prefix: '110001', bin: 'parliament' }]);
  await page.locator('#plans-body tr', { hasText: 'hub-north' }).waitFor();
  assert.equal((await apiJson('/api/v1/route/110001?plan=hub-north')).body.bin, 'parliament');

  // The page routes by it: a pincode no rule matches goes to the fallback bin.
  await page.locator('#p-try').fill('560001');
  await page.locator('#p-try').press('Enter');
  await page.locator('#plan-route-bin').filter({ hasText: 'floor' }).waitFor();
  assert.match(await page.locator('#plan-route-msg').textContent(), /fallback/);
  assert.doesNotMatch(await page.locator('#plan-route-msg').textContent(), /not in the registry/);
  // A pincode the registry does not hold is routed too, and the answer says it is not there.
  await page.locator('#p-try').fill('999999');
  await page.locator('#p-try').press('Enter');
  await page.locator('#plan-route-msg').filter({ hasText: '999999 is not in the registry' }).waitFor();
  assert.match(await page.locator('#plan-route-msg').textContent(), /999999 goes to bin floor/);

  // A prefix that starts with 0 can match no pincode: the server refuses it, naming the line,
  // and the saved plan is unchanged.
  await page.locator('#p-rules').fill('prefix,bin\n*,floor\n11,delhi\n01,nowhere\n');
  await page.getByRole('button', { name: 'Save plan' }).click();
  const refusal = page.locator('#plan-msg [role="alert"]');
  await refusal.waitFor();
  assert.match(await refusal.textContent(), /HTTP 400/);
  assert.match(await refusal.textContent(), /line 4/);
  assert.deepEqual((await apiJson('/api/v1/sortplans/hub-north')).body.rules, stored.body.rules);
  // A second new plan of the same name is refused, never saved over the first.
  await page.getByRole('button', { name: 'New plan' }).click();
  await page.getByRole('button', { name: 'Discard my changes' }).click();
  await page.locator('#p-name').fill('hub-north');
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'exists already' }).waitFor();
  assert.match(await page.locator('#plan-msg').textContent(), /HTTP 412/);
  assert.deepEqual((await apiJson('/api/v1/sortplans/hub-north')).body.rules, stored.body.rules);
  await screenshot(page, 'registry-plans');
  assert.deepEqual(page.problems, []);
});

test('a save over someone else\'s newer save is refused and keeps the text typed', async () => {
  const put = (etagHeaders, body) => fetch(`${session.server.url}/api/v1/sortplans/hub-race`, {
    method: 'PUT', body,
    headers: { Authorization: `Bearer ${session.server.adminToken}`, 'Content-Type': 'text/csv', ...etagHeaders },
  });
  assert.equal((await put({}, 'prefix,bin\n*,manual\n1,north\n')).status, 201);
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Open plan hub-race' }).click();
  await page.locator('#plan-edit-h').filter({ hasText: 'Plan hub-race' }).waitFor();
  // Another admin saves while this page has the plan open.
  assert.equal((await put({}, 'prefix,bin\n*,manual\n1,north\n2,west\n')).status, 200);
  const mine = 'prefix,bin\n*,manual\n1,north\n3,south\n';
  await page.locator('#p-rules').fill(mine);
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'Someone saved this plan after you opened it' }).waitFor();
  assert.equal(await page.locator('#p-rules').inputValue(), mine);
  const kept = await apiJson('/api/v1/sortplans/hub-race');
  assert.deepEqual(kept.body.rules.map((r) => r.prefix), ['1', '2']);
  // Opening the saved plan shows the other admin's version; saved on it, the change is kept.
  await page.getByRole('button', { name: 'Discard my text and open the saved hub-race' }).click();
  await valueHolds(page, '#p-rules', '2,west');
  await page.locator('#p-rules').fill('prefix,bin\n*,manual\n1,north\n2,west\n3,south\n');
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'Saved hub-race: 3 rules' }).waitFor();
  assert.deepEqual((await apiJson('/api/v1/sortplans/hub-race')).body.rules.map((r) => r.bin), ['north', 'west', 'south']);
  assert.deepEqual(page.problems, []);
});

test('unsaved changes are not dropped by opening another plan', async () => {
  const page = await openRegistry();
  await page.getByRole('button', { name: 'Open plan default' }).click();
  await page.locator('#plan-edit-h').filter({ hasText: 'Plan default' }).waitFor();
  await page.locator('#p-description').fill('edited, not saved');
  await page.getByRole('button', { name: 'New plan' }).click();
  await page.getByRole('alertdialog', { name: 'Unsaved changes' }).waitFor();
  await page.getByRole('button', { name: 'Keep editing' }).click();
  assert.equal(await page.locator('#p-description').inputValue(), 'edited, not saved');
  assert.equal(await page.locator('#plan-edit-h').textContent(), 'Plan default');
  // Escape is Keep editing too.
  await page.getByRole('button', { name: 'Close' }).click();
  await page.getByRole('button', { name: 'Discard my changes' }).press('Escape');
  assert.equal(await page.getByRole('alertdialog').count(), 0);
  assert.equal(await page.locator('#p-description').inputValue(), 'edited, not saved');
  await page.getByRole('button', { name: 'Close' }).click();
  await page.getByRole('button', { name: 'Discard my changes' }).click();
  assert.ok(await page.locator('#plan-form').isHidden());
  assert.notEqual((await apiJson('/api/v1/sortplans/default')).body.description, 'edited, not saved');
  assert.deepEqual(page.problems, []);
});

test('a plan is deleted after a confirmation, and Undo restores it whole', async () => {
  // More rules than the server reads as JSON (250,000 items, 3 a rule): put back as JSON the
  // undo was refused. A bin with a comma and quotes checks the page's CSV against the server's.
  const rows = ['prefix,bin', '*,floor', '4,"west, ""A"""',
    ...Array.from({ length: 84_000 }, (_, i) => `${500000 + i},b${i % 50}`)];
  const created = await fetch(`${session.server.url}/api/v1/sortplans/hub-gone?description=to%20be%20deleted`, {
    method: 'PUT', body: `${rows.join('\n')}\n`,
    headers: { Authorization: `Bearer ${session.server.adminToken}`, 'Content-Type': 'text/csv' },
  });
  assert.equal(created.status, 201);
  const before = await apiJson('/api/v1/sortplans/hub-gone');
  const page = await openRegistry();
  page.setDefaultTimeout(60_000);  // 84,000 rules are read, deleted and put back: seconds each
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Open plan hub-gone' }).click();
  await valueHolds(page, '#p-rules', 'west, ""A""');
  const csv = await (await fetch(`${session.server.url}/api/v1/sortplans/hub-gone?format=csv`)).text();
  assert.equal(await page.locator('#p-rules').inputValue(), csv);
  await page.getByRole('button', { name: 'Delete…' }).click();
  // Escape answers No: nothing is deleted.
  await page.getByRole('button', { name: 'Delete hub-gone' }).press('Escape');
  assert.equal((await apiJson('/api/v1/sortplans/hub-gone')).status, 200);
  await page.getByRole('button', { name: 'Delete…' }).click();
  await page.getByRole('button', { name: 'Delete hub-gone' }).click();
  await page.locator('#plans-msg').filter({ hasText: 'Deleted hub-gone.' }).waitFor();
  assert.equal((await apiJson('/api/v1/sortplans/hub-gone')).status, 404);
  assert.equal(await page.locator('#plans-body tr', { hasText: 'hub-gone' }).count(), 0);
  await page.getByRole('button', { name: 'Undo' }).click();
  await page.locator('#plans-msg').filter({ hasText: 'Restored hub-gone.' }).waitFor();
  const after = await apiJson('/api/v1/sortplans/hub-gone');
  assert.equal(after.status, 200);
  assert.equal(after.etag, before.etag, 'restored whole: the same version');
  await page.locator('#plans-body tr', { hasText: 'hub-gone' }).waitFor();
  assert.deepEqual(page.problems, []);
});

test('a plan deleted while it is edited: the open that fails leaves the editor as it was, and Save offers it as a new plan', async () => {
  const put = (name, body) => fetch(`${session.server.url}/api/v1/sortplans/${name}`, {
    method: 'PUT', body, headers: { Authorization: `Bearer ${session.server.adminToken}`, 'Content-Type': 'text/csv' },
  });
  const remove = (name) => fetch(`${session.server.url}/api/v1/sortplans/${name}`, {
    method: 'DELETE', headers: { Authorization: `Bearer ${session.server.adminToken}` },
  });
  assert.equal((await put('hub-a', 'prefix,bin\n*,manual\n1,north\n')).status, 201);
  assert.equal((await put('hub-b', 'prefix,bin\n*,manual\n2,west\n')).status, 201);
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Open plan hub-a' }).click();
  await valueHolds(page, '#p-rules', '1,north');
  const mine = 'prefix,bin\n*,manual\n1,north\n3,south\n';
  await page.locator('#p-rules').fill(mine);
  // Another admin deletes hub-b; opening it over the edits fails, and the edits stay, guarded.
  assert.equal((await remove('hub-b')).status, 200);
  await page.getByRole('button', { name: 'Open plan hub-b' }).click();
  await page.getByRole('button', { name: 'Discard my changes' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'HTTP 404' }).waitFor();
  assert.equal(await page.locator('#plan-edit-h').textContent(), 'Plan hub-a');
  assert.equal(await page.locator('#p-rules').inputValue(), mine);
  await page.getByRole('button', { name: 'Close' }).click();
  await page.getByRole('alertdialog', { name: 'Unsaved changes' }).waitFor();
  await page.getByRole('button', { name: 'Keep editing' }).click();
  // Now hub-a goes too: the save is refused, said to be a deletion, and offered as a new plan.
  assert.equal((await remove('hub-a')).status, 200);
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'Someone deleted this plan after you opened it' }).waitFor();
  assert.equal(await page.locator('#p-rules').inputValue(), mine);
  await page.getByRole('button', { name: 'Save it as a new plan' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'Saved hub-a: 2 rules' }).waitFor();
  assert.deepEqual((await apiJson('/api/v1/sortplans/hub-a')).body.rules.map((r) => r.bin), ['north', 'south']);
  assert.deepEqual(page.problems, []);
});

test('a name a web address cannot carry, or a description over its limit, is refused before it is sent', async () => {
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  let sent = 0;
  page.on('request', (request) => { if (request.method() === 'PUT') ++sent; });
  await page.getByRole('button', { name: 'New plan' }).click();
  for (const name of ['a/b', '..', 'x&y', 'n'.repeat(65)]) {
    await page.locator('#p-name').fill(name);
    await page.getByRole('button', { name: 'Save plan' }).click();
    await page.locator('#plan-msg [role="alert"]').filter({ hasText: /Name not usable|Name too long/ }).waitFor();
  }
  await page.locator('#p-name').fill('hub-long');
  await page.locator('#p-description').fill('d'.repeat(201));
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.locator('#plan-msg [role="alert"]').filter({ hasText: 'Description too long' }).waitFor();
  assert.equal(sent, 0);
  assert.equal((await apiJson('/api/v1/sortplans/hub-long')).status, 404);
  assert.deepEqual(page.problems, []);
});

test('while a save is on its way the plan cannot be closed, deleted or swapped for another', async () => {
  const put = (name, body) => fetch(`${session.server.url}/api/v1/sortplans/${name}`, {
    method: 'PUT', body,
    headers: { Authorization: `Bearer ${session.server.adminToken}`, 'Content-Type': 'text/csv' },
  });
  assert.equal((await put('hub-slow', 'prefix,bin\n*,manual\n1,north\n')).status, 201);
  assert.equal((await put('hub-other', 'prefix,bin\n*,manual\n2,west\n')).status, 201);
  const page = await openRegistry();
  await page.locator('#token').fill(session.server.adminToken);
  await page.getByRole('button', { name: 'Open plan hub-slow' }).click();
  await page.locator('#plan-edit-h').filter({ hasText: 'Plan hub-slow' }).waitFor();
  // The save is held in the browser until the test lets it go.
  let release;
  const released = new Promise((done) => { release = done; });
  await page.route('**/api/v1/sortplans/hub-slow?*', async (route) => {
    if (route.request().method() !== 'PUT') return route.continue();
    await released;
    return route.continue();
  });
  await page.locator('#p-rules').fill('prefix,bin\n*,manual\n1,north\n3,south\n');
  await page.getByRole('button', { name: 'Save plan' }).click();
  await page.waitForFunction(() => document.getElementById('plan-fields').disabled);
  assert.equal(await page.locator('#plan-close').isDisabled(), true);
  assert.equal(await page.locator('#plan-delete').isDisabled(), true);
  // Another plan from the list, or a new one, is not opened over the save.
  await page.getByRole('button', { name: 'Open plan hub-other' }).click();
  await page.locator('#plan-msg').filter({ hasText: 'The plan is being saved' }).waitFor();
  await page.getByRole('button', { name: 'New plan' }).click();
  assert.match(await page.locator('#plan-edit-h').textContent(), /Plan hub-slow/);
  assert.equal(await page.locator('#plan-confirm').textContent(), '');
  release();
  await page.locator('#plan-msg').filter({ hasText: 'Saved hub-slow: 2 rules' }).waitFor();
  assert.deepEqual((await apiJson('/api/v1/sortplans/hub-slow')).body.rules.map((r) => r.bin), ['north', 'south']);
  // Given back with the saved plan, before the list is read again.
  assert.equal(await page.locator('#plan-close').isDisabled(), false);
  assert.equal(await page.locator('#plan-delete').isDisabled(), false);
  // Once saved, the other plan opens as before.
  await page.getByRole('button', { name: 'Open plan hub-other' }).click();
  await page.locator('#plan-edit-h').filter({ hasText: 'Plan hub-other' }).waitFor();
  assert.deepEqual(page.problems, []);
});
