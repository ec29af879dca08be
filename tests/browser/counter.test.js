// Dispatch counter: lookup, label preview, single and batch PDF downloads, and a bad token.
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { readFile } from 'node:fs/promises';
import { test } from 'node:test';
import { addPincode, createToken, newPage, screenshot, serverAndBrowser, textLefts } from './harness.js';

let server;
let browser;
let counterToken;

serverAndBrowser(async (session) => {
  ({ server, browser } = session);
  counterToken = await createToken(server, 'counter');
});

// poppler-utils is in scripts/debian-packages-test.txt: without it these throw, and the test fails.
function pdfPageSize(path) {
  const info = execFileSync('pdfinfo', [path], { encoding: 'utf8' });
  return { pages: Number(info.match(/^Pages:\s+(\d+)/m)[1]), size: info.match(/^Page size:\s+(.*?) pts/m)[1] };
}

function pdfLines(path) {
  return execFileSync('pdftotext', [path, '-'], { encoding: 'utf8' }).split('\n').filter(Boolean);
}

// The counter page with `pins` looked up (and a counter token pasted first unless `token` is
// empty): the steps most tests start with.
async function counterWith(pins, { token = counterToken } = {}) {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  if (token) await page.locator('#token').fill(token);
  await page.locator('#pins').fill(pins);
  await page.getByRole('button', { name: 'Look up' }).click();
  return page;
}

test('counter looks up pincodes, previews a label and downloads single and batch PDFs', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  assert.equal(await page.getByText('Ctrl+Enter').isVisible(), true);  // a desktop has a keyboard
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001\n560001, 999999 12345');
  await page.getByRole('button', { name: 'Look up' }).click();

  const row = page.locator('tr[data-pincode="110001"]');
  await row.waitFor();
  assert.match(await row.textContent(), /Bengali Market/);
  assert.equal((await row.locator('.district').textContent()).trim(), 'Central Delhi');
  assert.match(await page.locator('tr.is-error').first().textContent(), /not found.*999999 is not in the registry/);
  assert.match(await page.locator('tr.is-error').nth(1).textContent(), /Not a pincode/);

  const preview = page.locator('#label-preview');
  await preview.waitFor();
  await page.waitForFunction(() => document.getElementById('label-preview')?.naturalWidth > 0);
  const size = await preview.evaluate((img) => [img.naturalWidth, img.naturalHeight]);
  assert.ok(Math.abs(size[1] / size[0] - 1.5) < 0.01, `100x150 mm preview aspect, got ${size}`);
  await screenshot(page, 'counter');

  const [single] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name: 'Download PDF' }).click()]);
  assert.equal(single.suggestedFilename(), 'label-110001.pdf');
  const singlePath = await single.path();
  assert.equal((await readFile(singlePath)).subarray(0, 5).toString(), '%PDF-');
  assert.deepEqual(pdfPageSize(singlePath), { pages: 1, size: '283.465 x 425.197' });
  // No plan was picked: the label carries the default plan's bin, the one the routing API gives.
  assert.equal(await page.locator('#plan').inputValue(), 'default');
  assert.match(await page.locator('#preview figcaption').textContent(), /plan default/);
  const routed = await (await fetch(`${server.url}/api/v1/route/110001`)).json();
  const lines = pdfLines(singlePath);
  assert.ok(lines.includes('plan default') && lines.includes(routed.bin), `bin ${routed.bin} in ${lines.join(' | ')}`);

  await page.getByLabel('A6').check();
  await page.waitForFunction(() => /A6/.test(document.querySelector('#preview figcaption')?.textContent || ''));
  const batchButton = page.getByRole('button', { name: /Batch PDF \(2 labels\)/ });
  const [batch] = await Promise.all([page.waitForEvent('download'), batchButton.click()]);
  const batchPath = await batch.path();
  assert.equal((await readFile(batchPath)).subarray(0, 5).toString(), '%PDF-');
  assert.deepEqual(pdfPageSize(batchPath), { pages: 2, size: '297.638 x 419.528' });
  await page.getByText('2 labels in one PDF downloaded').waitFor();
  assert.deepEqual(page.problems, []);
});

test('the counter keeps its label size and sort plan over a reload, and labels are made with them', async () => {
  const put = await fetch(`${server.url}/api/v1/sortplans/counter-kept`, {
    method: 'PUT',
    headers: { Authorization: `Bearer ${server.adminToken}`, 'Content-Type': 'text/csv' },
    body: 'prefix,bin\n*,manual\n110001,parliament\n',
  });
  assert.ok([200, 201].includes(put.status), `PUT counter-kept: ${put.status}`);
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#plan option[value="counter-kept"]').waitFor({ state: 'attached' });
  await page.getByLabel('A6').check();
  await page.locator('#plan').selectOption('counter-kept');
  await page.reload();
  await page.locator('#plan option[value="counter-kept"]').waitFor({ state: 'attached' });
  await page.waitForFunction(() => document.getElementById('plan').value === 'counter-kept');
  assert.equal(await page.getByLabel('A6').isChecked(), true);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001');
  await page.getByRole('button', { name: 'Look up' }).click();
  const caption = page.locator('#preview figcaption');
  await caption.filter({ hasText: 'counter-kept' }).waitFor();
  assert.match(await caption.textContent(), /A6/);
  assert.deepEqual(page.problems, []);
});

test('a PDF still on its way when the clerk picks another row is saved under its own pincode', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001 560001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#preview figcaption').filter({ hasText: '110001' }).waitFor();
  // The real server answers; its answer for 110001's PDF is only held back until the clerk has
  // picked 560001.
  let release;
  const held = new Promise((resolveHeld) => { release = resolveHeld; });
  await page.route('**/api/v1/labels/110001.pdf*', async (route) => { await held; await route.continue(); });
  const download = page.getByRole('button', { name: 'Download PDF' });
  const saved = page.waitForEvent('download');
  await download.click();
  await page.getByRole('button', { name: 'Preview the label for 560001' }).click();
  await page.locator('#preview figcaption').filter({ hasText: '560001' }).waitFor();
  assert.equal(await download.isDisabled(), true, 'busy while its request runs, whatever was picked');
  release();
  const file = await saved;
  assert.equal(file.suggestedFilename(), 'label-110001.pdf');
  assert.ok(pdfLines(await file.path()).includes('110 001'), pdfLines(await file.path()).join(' | '));
  await page.getByText('Label for 110001 downloaded (label-110001.pdf).').waitFor();
  assert.equal(await download.isDisabled(), false, 'free again for the row now picked');
  assert.deepEqual(page.problems, []);
});

test('a clerk picks the office a label prints, row by row', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001\n110001');  // two parcels, two addressees
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  const second = page.locator('tr[data-row="1"]');
  const choice = second.getByLabel('Office printed on the label for 110001');
  assert.equal(await choice.inputValue(), 'Bengali Market');  // the record's own comes first
  assert.equal(await choice.getAttribute('title'), 'Bengali Market');  // whole, where cut
  await choice.selectOption('Janpath');
  assert.equal(await choice.getAttribute('title'), 'Janpath');
  // Two rows of one pincode: their controls' names say which row they are.
  await page.getByRole('button', { name: 'Preview the label for 110001 (row 2)', exact: true }).click();
  assert.equal(await page.getByRole('checkbox', { name: 'Print a label for 110001 (row 1)', exact: true }).count(), 1);
  await page.waitForFunction(() => /Janpath/.test(document.getElementById('label-preview')?.alt || ''));
  // Only the row previewed is marked, not every row of that pincode.
  assert.equal(await page.locator('tr.is-selected').count(), 1);
  assert.equal(await page.locator('tr.is-selected').getAttribute('data-row'), '1');
  assert.equal(await page.locator('tr[aria-current="true"]').getAttribute('data-row'), '1');
  // The caption under the preview names the office too, not only the image's alt text.
  assert.match(await page.locator('#preview figcaption').innerText(), /Janpath/);

  const [single] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name: 'Download PDF' }).click()]);
  const singleLines = pdfLines(await single.path());
  assert.ok(singleLines.includes('Janpath') && !singleLines.includes('Bengali Market'), singleLines.join(' | '));

  const [batch] = await Promise.all([page.waitForEvent('download'),
    page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).click()]);
  const batchPath = await batch.path();
  const pageText = (n) => execFileSync('pdftotext', ['-f', String(n), '-l', String(n), batchPath, '-'], { encoding: 'utf8' });
  assert.match(pageText(1), /Bengali Market/);
  assert.match(pageText(2), /Janpath/);
  assert.doesNotMatch(pageText(2), /Bengali Market/);
  await screenshot(page, 'counter-office');

  // 140119's offices lie in three districts: the row shows the chosen office's district and
  // state, as the label prints them.
  await page.locator('#pins').fill('140119');
  await page.getByRole('button', { name: 'Look up' }).click();
  const row = page.locator('tr[data-pincode="140119"]');
  await row.waitFor();
  assert.equal((await row.locator('.district').textContent()).trim(), 'Chandigarh');
  await row.getByLabel('Office printed on the label for 140119').selectOption('Bajrur');
  assert.equal((await row.locator('.district').textContent()).trim(), 'Ropar');
  assert.equal((await row.locator('.state').textContent()).trim(), 'Punjab');
  await page.waitForFunction(() => /Bajrur/.test(document.getElementById('label-preview')?.alt || ''));
  const [bajrur] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name: 'Download PDF' }).click()]);
  const bajrurLines = pdfLines(await bajrur.path());
  assert.ok(bajrurLines.includes('Ropar, Punjab'), bajrurLines.join(' | '));
  await row.getByLabel('Office printed on the label for 140119').selectOption('Abiana');
  assert.equal((await row.locator('.district').textContent()).trim(), 'Chandigarh');
  assert.deepEqual(page.problems, []);
});

test('a batch over the server\'s limit is made as several PDFs of at most that many labels', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  // 101 rows: 110001 a hundred times, then 560001 (the last label, alone in the second PDF).
  await page.locator('#pins').fill([...Array(100).fill('110001'), '560001'].join('\n'));
  await page.getByRole('button', { name: 'Look up' }).click();
  const batchButton = page.getByRole('button', { name: /Batch PDF \(101 labels\)/ });
  await batchButton.waitFor();
  const downloads = [];
  page.on('download', (download) => downloads.push(download));
  const posts = [];
  page.on('request', (request) => {
    if (request.method() === 'POST' && request.url().endsWith('/api/v1/labels')) posts.push(request.postDataJSON().pincodes.length);
  });
  await batchButton.click();
  // Refused whole (the server's 413 gives its limit, 100), then made as 100 + 1.
  await page.locator('#print-msg').filter({ hasText: '101 labels downloaded in 2 PDFs of at most 100' }).waitFor();
  assert.deepEqual(posts, [101, 100, 1]);
  assert.deepEqual(downloads.map((d) => d.suggestedFilename()),
    ['labels-110001-100-part1of2.pdf', 'labels-560001-1-part2of2.pdf']);
  const [first, second] = await Promise.all(downloads.map((d) => d.path()));
  assert.equal(pdfPageSize(first).pages, 100);
  assert.equal(pdfPageSize(second).pages, 1);
  assert.match(execFileSync('pdftotext', [second, '-'], { encoding: 'utf8' }), /560 001/);
  assert.equal(await page.locator('#print-msg [role="alert"]').count(), 0);
  // All made: the rows stay ticked (a jammed printer may want the batch again).
  assert.equal(await page.getByRole('button', { name: /Batch PDF \(101 labels\)/ }).count(), 1);

  // A later part that fails: the parts saved are unticked, so that the next click asks only for
  // the rest instead of printing the first hundred twice.
  let calls = 0;
  await page.route('**/api/v1/labels', (route) => (++calls === 3 ? route.abort() : route.continue()));
  await page.getByRole('button', { name: /Batch PDF \(101 labels\)/ }).click();
  await page.locator('#print-msg [role="alert"]').filter({ hasText: 'Already downloaded, and unticked: labels-110001-100-part1of2.pdf' }).waitFor();
  await page.getByRole('button', { name: /Batch PDF \(1 label\)/ }).waitFor();
  await page.unroute('**/api/v1/labels');
  const rest = page.waitForEvent('download');
  await page.getByRole('button', { name: /Batch PDF \(1 label\)/ }).click();
  assert.equal((await rest).suggestedFilename(), 'labels-560001-1.pdf');
  const pageErrors = page.problems.filter((p) => !/net::ERR_FAILED/.test(p));
  assert.deepEqual(pageErrors, []);
});

test('counter shows the problem detail for a wrong token', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill('pt_999_notarealtokennotarealtokennotarealtokenxx');
  await page.locator('#pins').fill('110001');
  await page.locator('#pins').press('Control+Enter');
  const alert = page.locator('#preview [role="alert"]');
  await alert.waitFor();
  assert.match(await alert.textContent(), /HTTP 401/);
  assert.match(await alert.textContent(), /token/i);
});

test('the counter page fits a phone screen', async () => {
  const page = await newPage(browser, { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('400001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  const overflow = await page.evaluate(() => document.documentElement.scrollWidth - window.innerWidth);
  assert.ok(overflow <= 0, `page is ${overflow}px wider than the phone screen`);
  // A phone has no Ctrl key: the shortcut is not offered there, the rest of the hint is.
  assert.equal(await page.getByText('Ctrl+Enter').isVisible(), false);
  assert.equal(await page.getByText('A pincode listed twice prints twice.').isVisible(), true);
  await screenshot(page, 'counter-phone');
});

test('a list looked up again while the first lookup runs shows only the latest list', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  // The long list's last lookup is held back until the short list has been drawn, so the long
  // one is surely still running when the clerk submits the short one.
  let reached;
  const atEnd = new Promise((resolveAtEnd) => { reached = resolveAtEnd; });
  let release;
  const held = new Promise((resolveHeld) => { release = resolveHeld; });
  await page.route('**/api/v1/pincodes/110600', async (route) => {
    reached();
    await held;
    await route.continue().catch(() => {});  // the page may have stopped asking meanwhile
  });
  const pins = page.locator('#pins');
  await pins.fill(Array.from({ length: 600 }, (_, i) => String(110001 + i)).join('\n'));
  await pins.press('Control+Enter');
  await atEnd;
  await pins.fill('560001');
  await pins.press('Control+Enter');
  await page.locator('#preview figcaption').filter({ hasText: '560001' }).waitFor();
  release();
  const lookupButton = page.getByRole('button', { name: 'Look up' });
  // Both lookups over, the button is free again.
  await page.waitForFunction(() => {
    const button = document.getElementById('lookup');
    return !button.disabled && !button.hasAttribute('aria-busy');
  });
  assert.equal(await lookupButton.isEnabled(), true);
  assert.equal(await page.locator('#results-body tr').count(), 1);
  assert.equal(await page.locator('#results-body tr').getAttribute('data-pincode'), '560001');
  assert.match(await page.locator('#results-caption').textContent(), /^1 pincode, 1 found/);
  assert.match(await page.locator('#label-preview').getAttribute('alt'), /^Label for 560001/);
  const [single] = await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name: 'Download PDF' }).click()]);
  assert.equal(single.suggestedFilename(), 'label-560001.pdf');
  assert.ok(pdfLines(await single.path()).includes('560 001'));
  assert.deepEqual(page.problems, []);
});

test('Look up is free again after a lookup replaced another that was still running', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  // Each lookup's request is held until the test lets it go: the first list's, then the second's.
  const gates = new Map();
  const gate = (pin) => {
    let open;
    const opened = new Promise((resolveOpen) => { open = resolveOpen; });
    let reached;
    const arrived = new Promise((resolveArrived) => { reached = resolveArrived; });
    gates.set(pin, { open, opened, reached, arrived });
  };
  gate('110001');
  gate('560001');
  await page.route(/\/api\/v1\/pincodes\/(110001|560001)$/, async (route) => {
    const held = gates.get(route.request().url().slice(-6));
    held.reached(route.request());
    await held.opened;
    await route.continue().catch(() => {});  // the page may have stopped asking meanwhile
  });
  const firstFailed = new Promise((resolveFailed) => {
    page.on('requestfailed', (request) => { if (request.url().endsWith('/pincodes/110001')) resolveFailed(); });
  });
  const pins = page.locator('#pins');
  await pins.fill('110001');
  await pins.press('Control+Enter');
  await gates.get('110001').arrived;
  await pins.fill('560001');
  await pins.press('Control+Enter');
  await gates.get('560001').arrived;
  // The first lookup ends first: drawn (the old page drew it), or stopped by the second.
  gates.get('110001').open();
  await Promise.race([firstFailed, page.locator('#preview figcaption').filter({ hasText: '110001' }).waitFor()]);
  gates.get('560001').open();
  await page.locator('#preview figcaption').filter({ hasText: '560001' }).waitFor();
  await page.waitForFunction(() => !document.getElementById('lookup').hasAttribute('aria-busy'));
  assert.equal(await page.getByRole('button', { name: 'Look up' }).isEnabled(), true, 'Look up is not left disabled');
  assert.equal(await page.locator('#results-body tr').count(), 1);
  assert.equal(await page.locator('#results-body tr').getAttribute('data-pincode'), '560001');
  assert.deepEqual(page.problems, []);
});

test('a new lookup clears the message about the previous list\'s labels', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001 560001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  await Promise.all([page.waitForEvent('download'), page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).click()]);
  await page.getByText('2 labels in one PDF downloaded').waitFor();
  await page.locator('#pins').fill('400001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#preview figcaption').filter({ hasText: '400001' }).waitFor();
  assert.equal(await page.locator('#print-msg').textContent(), '');
  assert.deepEqual(page.problems, []);
});

test('pincodes pasted with no-break or zero-width spaces are read as typed', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  // A no-break space inside "110 001" and between two pincodes; zero-width spaces and a byte
  // order mark around and inside others (as text copied from web pages and spreadsheets has).
  await page.locator('#pins').fill('110\u00a0001\u00a0560001\u200b\n\ufeff400001, 140\u200b119\u2003600001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  const listed = await page.locator('#results-body tr').evaluateAll((trs) => trs.map((tr) => tr.dataset.pincode || tr.textContent));
  assert.deepEqual(listed, ['110001', '560001', '400001', '140119', '600001']);
  assert.equal(await page.locator('tr.is-error').count(), 0);
  assert.deepEqual(page.problems, []);
});

test('pincodes typed in Devanagari, Tamil or Urdu digits are read as the pincodes they are', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  // A Hindi, Tamil or Urdu keyboard types its own digits; they were refused as "not a pincode".
  await page.locator('#pins').fill('\u0967\u0967\u0966\u0966\u0966\u0967 \u0bEB\u0bEC\u0be6\u0be6\u0be6\u0be7 \u06f4\u06f0\u06f0\u06f0\u06f0\u06f1');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  const listed = await page.locator('#results-body tr').evaluateAll((trs) => trs.map((tr) => tr.dataset.pincode || tr.textContent));
  assert.deepEqual(listed, ['110001', '560001', '400001']);
  assert.equal(await page.locator('tr.is-error').count(), 0);
  assert.deepEqual(page.problems, []);
});

test('a token pasted with invisible characters is used as it is meant, and Forget takes its preview', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  // A zero-width space, a byte order mark and a bidi mark, as a token copied from a chat or a PDF
  // can carry; the browser refused to send such a header with its own message, naming no field.
  await page.locator('#token').fill(`\u200b ${counterToken}\ufeff\u200e\n`);
  await page.locator('#pins').fill('110001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  assert.equal(await page.evaluate(() => sessionStorage.getItem('pintag.token.counter')), counterToken);
  await page.locator('#token-forget').click();
  await page.locator('#preview').filter({ hasText: 'Paste a counter token above' }).waitFor();
  assert.equal(await page.locator('#label-preview').count(), 0);
  assert.deepEqual(page.problems, []);
});

test('a single label refused as retired marks its row retired, as a refused batch does', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('500001\n110001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  assert.equal(await page.locator('tr.is-selected').getAttribute('data-pincode'), '500001');
  // Retired by an admin elsewhere after the clerk looked it up; the clerk downloads its label.
  const retired = await fetch(`${server.url}/api/v1/pincodes/500001/retire`,
    { method: 'POST', headers: { Authorization: `Bearer ${server.adminToken}` } });
  assert.equal(retired.status, 200);
  await page.getByRole('button', { name: 'Download PDF' }).click();
  const alert = page.locator('#print-msg [role="alert"]');
  await alert.waitFor();
  assert.match(await alert.textContent(), /HTTP 410/);
  const row = page.locator('tr[data-pincode="500001"]');
  await row.filter({ hasText: /retired/i }).waitFor();
  assert.equal(await row.getByRole('checkbox').isChecked(), false);
  assert.equal(await row.getByRole('checkbox').isDisabled(), true);
  assert.match(await page.locator('#preview').textContent(), /500001 is retired/);
  assert.ok(await page.getByRole('button', { name: /Batch PDF \(1 label\)/ }).isVisible());
  assert.deepEqual(page.problems, []);
});

test('a batch refused for one pincode names that pincode\'s row and marks it retired', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  // Rows 1 and 2 are not printed, so the server's pincodes[2] is the table's row 5.
  await page.locator('#pins').fill('12345\n999999\n110001\n400001\n700001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#label-preview').waitFor();
  // Retired by an admin elsewhere after the clerk looked it up.
  const retired = await fetch(`${server.url}/api/v1/pincodes/700001/retire`,
    { method: 'POST', headers: { Authorization: `Bearer ${server.adminToken}` } });
  assert.equal(retired.status, 200);
  await page.getByRole('button', { name: /Batch PDF \(3 labels\)/ }).click();
  const alert = page.locator('#print-msg [role="alert"]');
  await alert.waitFor();
  const text = await alert.textContent();
  assert.match(text, /HTTP 410/);
  assert.match(text, /row 5: pincode 700001 was retired/);
  assert.doesNotMatch(text, /pincodes\[/);
  const row = page.locator('tr[data-pincode="700001"]');
  assert.match(await row.textContent(), /retired/i);
  assert.equal(await row.getByRole('checkbox').isChecked(), false);
  assert.equal(await row.getByRole('checkbox').isDisabled(), true);
  assert.equal(await page.locator('tr.is-selected').getAttribute('data-pincode'), '110001');  // still previewed
  await screenshot(page, 'counter-retired');
  // The rest print without it.
  const [batch] = await Promise.all([page.waitForEvent('download'),
    page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).click()]);
  assert.deepEqual(pdfPageSize(await batch.path()), { pages: 2, size: '283.465 x 425.197' });
  assert.deepEqual(page.problems, []);
});

// Where each row's Preview button and office choice lie, against the table's visible box.
async function tableFit(page) {
  return page.evaluate(() => {
    const wrap = document.getElementById('results');
    const box = wrap.getBoundingClientRect();
    const left = box.left + wrap.clientLeft;
    const right = left + wrap.clientWidth;
    const previews = [...wrap.querySelectorAll('tbody button')].map((button) => {
      const r = button.getBoundingClientRect();
      return { name: button.getAttribute('aria-label'), inside: r.left >= left && r.right <= right + 0.5 };
    });
    // The width each office choice needs to show its chosen name whole.
    const offices = [...wrap.querySelectorAll('select')].map((select) => {
      const probe = select.cloneNode(false);
      probe.append(new Option(select.value));
      probe.style.cssText = 'position:absolute; visibility:hidden; width:auto; min-width:0; max-width:none';
      select.parentElement.append(probe);
      const need = probe.offsetWidth;
      probe.remove();
      return { name: select.value, whole: select.offsetWidth >= need, width: select.offsetWidth, need };
    });
    return { overflow: wrap.scrollWidth - wrap.clientWidth, previews, offices };
  });
}

for (const [width, options] of [[1280, {}], [390, { isMobile: true, hasTouch: true }]]) {
  test(`every row's Preview and office name are in view at ${width} px`, async () => {
    const page = await newPage(browser, { viewport: { width, height: 900 }, ...options });
    await page.goto(`${server.url}/counter.html`);
    await page.locator('#token').fill(counterToken);
    // 140119's and 400001's districts and states are long single words; 999999 is an error row.
    await page.locator('#pins').fill('110001\n140119\n560001 400001 999999');
    await page.getByRole('button', { name: 'Look up' }).click();
    await page.locator('#label-preview').waitFor();
    await page.locator('tr[data-pincode="140119"]').getByLabel('Office printed on the label for 140119')
      .selectOption('Tibba Taparian');
    const fit = await tableFit(page);
    assert.equal(fit.previews.length, 4);
    assert.deepEqual(fit.previews.filter((p) => !p.inside), [], `Preview cut off (table ${fit.overflow} px too wide)`);
    assert.ok(fit.overflow <= 0, `table is ${fit.overflow} px wider than its card`);
    assert.deepEqual(fit.offices.filter((o) => !o.whole), [], 'office names cut short');
    // The district and state the label prints are still shown for each row.
    const row = page.locator('tr[data-pincode="140119"]');
    assert.equal((await row.locator('.district').textContent()).trim(), 'Rupnagar');
    assert.equal(await row.locator('.state').isVisible(), true);
    await page.getByRole('button', { name: 'Preview the label for 400001' }).click();
    await page.locator('#preview figcaption').filter({ hasText: '400001' }).waitFor();
    await screenshot(page, `counter-table-${width}`);
    assert.deepEqual(page.problems, []);
  });
}

test('a list looked up again keeps each listed row\'s office, tick and preview', async () => {
  const page = await counterWith('110001 560001\n110001');
  await page.locator('#label-preview').waitFor();
  await page.getByLabel('Office printed on the label for 110001 (row 3)', { exact: true }).selectOption('Janpath');
  await page.getByRole('checkbox', { name: 'Print a label for 560001', exact: true }).uncheck();
  await page.getByRole('button', { name: 'Preview the label for 110001 (row 3)', exact: true }).click();
  await page.waitForFunction(() => /Janpath/.test(document.getElementById('label-preview')?.alt || ''));
  await page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).waitFor();

  // One pincode more, put first: the rows already listed keep what the clerk chose.
  await page.locator('#pins').fill('400001\n110001 560001\n110001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('tr[data-pincode="400001"]').waitFor();
  await page.getByRole('button', { name: /Batch PDF \(3 labels\)/ }).waitFor();
  assert.equal(await page.getByLabel('Office printed on the label for 110001 (row 4)', { exact: true }).inputValue(), 'Janpath');
  assert.equal(await page.getByLabel('Office printed on the label for 110001 (row 2)', { exact: true }).inputValue(), 'Bengali Market');
  assert.equal(await page.getByRole('checkbox', { name: 'Print a label for 560001', exact: true }).isChecked(), false);
  assert.equal(await page.getByRole('checkbox', { name: 'Print a label for 400001', exact: true }).isChecked(), true);
  // The label shown is still the one the clerk picked, with its office.
  await page.locator('#preview figcaption').filter({ hasText: 'Janpath' }).waitFor();
  assert.equal(await page.locator('tr.is-selected').getAttribute('data-row'), '3');
  const [batch] = await Promise.all([page.waitForEvent('download'),
    page.getByRole('button', { name: /Batch PDF \(3 labels\)/ }).click()]);
  const batchPath = await batch.path();
  const pageText = (n) => execFileSync('pdftotext', ['-f', String(n), '-l', String(n), batchPath, '-'], { encoding: 'utf8' });
  assert.deepEqual(pdfPageSize(batchPath).pages, 3);
  assert.match(pageText(2), /Bengali Market/);
  assert.match(pageText(3), /Janpath/);
  assert.doesNotMatch(pageText(3), /Bengali Market/);
  assert.deepEqual(page.problems, []);
});

test('a lookup the server cannot answer keeps the rows it had, and the clerk\'s choices in them', async () => {
  const page = await counterWith('110001 560001 400001');
  await page.locator('#label-preview').waitFor();
  await page.getByLabel('Office printed on the label for 110001', { exact: true }).selectOption('Janpath');
  await page.getByRole('checkbox', { name: 'Print a label for 400001', exact: true }).uncheck();
  await page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).waitFor();

  // The server out of reach for one lookup: the rows went "not checked", and the lookup after it
  // ticked 400001 again and put back 110001's own office, without a word.
  await page.route('**/api/v1/pincodes/*', (route) => route.abort());
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#lookup-msg [role="alert"]').waitFor();
  await page.getByRole('button', { name: 'Look up' }).and(page.locator(':not([aria-busy])')).waitFor();
  assert.equal(await page.locator('tr.is-error').count(), 0);
  assert.equal(await page.getByLabel('Office printed on the label for 110001', { exact: true }).inputValue(), 'Janpath');
  assert.equal(await page.getByRole('checkbox', { name: 'Print a label for 400001', exact: true }).isChecked(), false);
  await page.unroute('**/api/v1/pincodes/*');
  await page.getByRole('button', { name: 'Look up' }).click();
  // The lookup clears its message as it starts: done is the button free again.
  await page.getByRole('button', { name: 'Look up' }).and(page.locator(':not([aria-busy])')).waitFor();
  assert.equal(await page.locator('#lookup-msg [role="alert"]').count(), 0);
  assert.equal(await page.getByLabel('Office printed on the label for 110001', { exact: true }).inputValue(), 'Janpath');
  assert.equal(await page.getByRole('checkbox', { name: 'Print a label for 400001', exact: true }).isChecked(), false);
  assert.equal(await page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).count(), 1);
  assert.deepEqual(page.problems.filter((p) => !/net::ERR_FAILED/.test(p)), []);
});

test('leaving the page asks first while the table holds the clerk\'s choices', async () => {
  const page = await counterWith('110001 560001');
  await page.locator('#label-preview').waitFor();
  const asked = [];
  page.on('dialog', (dialog) => {
    asked.push(dialog.type());
    dialog.dismiss();
  });
  // A pasted list alone is pasted again: no question.
  const closed = page.waitForEvent('close');
  await page.close({ runBeforeUnload: true });
  await closed;
  assert.deepEqual(asked, []);

  const second = await counterWith('110001 560001');
  await second.locator('#label-preview').waitFor();
  await second.getByLabel('Office printed on the label for 110001', { exact: true }).selectOption('Janpath');
  const question = second.waitForEvent('dialog');
  await second.close({ runBeforeUnload: true });
  const dialog = await question;
  assert.equal(dialog.type(), 'beforeunload');
  await dialog.dismiss();
  assert.equal(second.isClosed(), false);
  await second.close();
});

test('a whole token pasted shows the label at once, and a label on its way says so over the old one', async () => {
  const page = await counterWith('110001 560001', { token: '' });
  await page.locator('#preview').filter({ hasText: 'Paste a counter token above' }).waitFor();
  // Pasted, the field keeping the focus: the label came only when the field lost it.
  await page.locator('#token').fill(counterToken);
  await page.locator('#label-preview').waitFor();
  assert.equal(await page.evaluate(() => document.activeElement?.id), 'token');

  // Another row's label held on its way: the one shown is dimmed, and the caption names the
  // pincode coming, where it named the old one while Download acted on the new.
  let release;
  const held = new Promise((resolve) => { release = resolve; });
  await page.route('**/api/v1/labels/560001.png*', async (route) => { await held; await route.continue(); });
  await page.getByRole('button', { name: 'Preview the label for 560001', exact: true }).click();
  await page.locator('#preview figcaption').filter({ hasText: 'Loading the label for 560001' }).waitFor();
  assert.equal(await page.locator('#preview').getAttribute('aria-busy'), 'true');
  assert.equal(await page.locator('#label-preview').evaluate((img) => getComputedStyle(img).opacity), '0.35');
  release();
  await page.waitForFunction(() => /560001/.test(document.getElementById('label-preview')?.alt || ''));
  await page.locator('#preview figcaption').filter({ hasText: /^560001/ }).waitFor();
  assert.equal(await page.locator('#label-preview').evaluate((img) => getComputedStyle(img).opacity), '1');
  assert.deepEqual(page.problems, []);
});

test('a long list says how far its lookup has come', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  const pins = Array.from({ length: 60 }, (_, i) => String(110001 + i));
  await page.locator('#pins').fill(pins.join('\n'));
  // Held after a few answers, so that the progress can be read before the lookup ends.
  let release;
  const held = new Promise((resolve) => { release = resolve; });
  await page.route('**/api/v1/pincodes/*', async (route) => {
    if (!route.request().url().endsWith('/110001')) await held;
    await route.continue();
  });
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#lookup-msg').filter({ hasText: /Looking up [1-9]\d* of 60 pincodes/ }).waitFor();
  release();
  await page.locator('#results-caption').filter({ hasText: /^60 pincodes/ }).waitFor();
  assert.equal((await page.locator('#lookup-msg').textContent()).trim(), '');
  assert.deepEqual(page.problems, []);
});

test('an empty lookup clears the table it replaced, and its Batch PDF', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001 560001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.getByRole('button', { name: /Batch PDF \(2 labels\)/ }).waitFor();
  await page.locator('#label-preview').waitFor();
  await page.locator('#pins').fill('   ');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#lookup-msg').filter({ hasText: 'Type or paste at least one pincode' }).waitFor();
  assert.equal(await page.locator('#results').isHidden(), true);
  const batch = page.locator('#batch-pdf');
  assert.equal(await batch.isDisabled(), true);
  assert.equal(await batch.textContent(), 'Batch PDF (0 labels)');
  assert.equal(await page.locator('#label-preview').count(), 0);
  assert.equal(await page.getByRole('button', { name: 'Download PDF' }).isDisabled(), true);
  assert.deepEqual(page.problems, []);
});

test('an office written right to left leaves the caption and the row in their order', async () => {
  const office = 'کراچی مرکزی ڈاک خانہ';
  await addPincode(server, '999002', [{ name: office, district: 'لاہور', state: 'پنجاب' }]);
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('999002');
  await page.getByRole('button', { name: 'Look up' }).click();
  const caption = page.locator('#preview figcaption');
  await caption.waitFor();
  assert.equal(await caption.textContent(), `999002 · ${office} · 100 × 150 mm · plan default`);
  // Left to right as written: the Urdu name kept to itself (its first word is its rightmost).
  const [pin, first, last, w, h, mm, plan] = await textLefts(page, '#preview figcaption',
    ['999002', 'کراچی', 'خانہ', '100', '150', 'mm', 'plan']);
  assert.ok(pin < last && last < first && first < w && w < h && h < mm && mm < plan,
    `caption drawn out of order: ${JSON.stringify({ pin, first, last, w, h, mm, plan })}`);
  // District, then state, as in every other row.
  const [district, state] = await textLefts(page, 'tr[data-pincode="999002"] .place', ['لاہور', 'پنجاب']);
  assert.ok(district < state, `state drawn before district: ${district}, ${state}`);
  await screenshot(page, 'counter-rtl-office');
  assert.deepEqual(page.problems, []);
});

test('a row retired after its office was changed shows its record\'s office and place', async () => {
  await addPincode(server, '999005', [{ name: 'Alpha Nagar', district: 'Alphapur', state: 'Alpha State' },
    { name: 'Beta Nagar', district: 'Betapur', state: 'Beta State' }]);
  const page = await newPage(browser);
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('999005 110001');
  await page.getByRole('button', { name: 'Look up' }).click();
  const row = page.locator('tr[data-pincode="999005"]');
  await row.getByLabel('Office printed on the label for 999005').selectOption('Beta Nagar');
  assert.equal(await row.locator('.district').textContent(), 'Betapur');
  await page.waitForFunction(() => /Beta Nagar/.test(document.getElementById('label-preview')?.alt || ''));
  const retired = await fetch(`${server.url}/api/v1/pincodes/999005/retire`,
    { method: 'POST', headers: { Authorization: `Bearer ${server.adminToken}` } });
  assert.equal(retired.status, 200);
  await page.getByRole('button', { name: 'Download PDF' }).click();
  await row.filter({ hasText: /retired/i }).waitFor();
  assert.match(await row.locator('td.office').textContent(), /^Alpha Nagar/);
  assert.equal(await row.locator('.district').textContent(), 'Alphapur');
  assert.equal(await row.locator('.state').textContent(), 'Alpha State');
  assert.deepEqual(page.problems, []);
});

test('on a phone, a row\'s Preview brings its label into view', async () => {
  const page = await newPage(browser, { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001 560001 400001 600001 700001 140119 380001 302001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('#preview figcaption').filter({ hasText: '110001' }).waitFor();
  const button = page.getByRole('button', { name: 'Preview the label for 302001' });
  await button.tap();
  await page.locator('#preview figcaption').filter({ hasText: '302001' }).waitFor();
  await page.waitForFunction(() => document.getElementById('label-preview')?.complete);
  // The scroll is smooth in some browsers: wait for it to settle.
  await page.waitForFunction(() => {
    const box = document.getElementById('label-preview').getBoundingClientRect();
    return box.top >= 0 && box.bottom <= window.innerHeight;
  }, null, { timeout: 5000 }).catch(() => {});
  const box = await page.locator('#label-preview').boundingBox();
  assert.ok(box.y >= 0 && box.y + box.height <= 844, `the label is out of view: ${JSON.stringify(box)}`);
  await screenshot(page, 'counter-phone-preview');
  assert.deepEqual(page.problems, []);
});

test('Open PDF to print shows the label in a new tab, and keeps it until that tab is closed', async () => {
  const page = await newPage(browser);
  // The page's clock, moved on by hand: minutes pass in an instant. The page's CSP keeps it from
  // fetching a blob: URL, so what it lets go is recorded as it lets it go.
  await page.clock.install();
  await page.addInitScript(() => {
    window.revokedUrls = [];
    const revoke = URL.revokeObjectURL.bind(URL);
    URL.revokeObjectURL = (url) => { window.revokedUrls.push(url); revoke(url); };
  });
  await page.goto(`${server.url}/counter.html`);
  await page.locator('#token').fill(counterToken);
  await page.locator('#pins').fill('110001');
  await page.getByRole('button', { name: 'Look up' }).click();
  await page.locator('tr[data-pincode="110001"]').waitFor();
  await page.waitForFunction(() => !document.getElementById('print-pdf').disabled);
  const [tab] = await Promise.all([page.context().waitForEvent('page'),
    page.getByRole('button', { name: 'Open PDF to print' }).click()]);
  await tab.waitForURL(/^blob:/);
  const url = tab.url();
  await page.getByText('The label for 110001 opened in a new tab').waitFor();
  const revoked = () => page.evaluate((u) => window.revokedUrls.includes(u), url);
  // Minutes later the clerk may still print, reload or save it from the tab.
  await page.clock.fastForward('05:00');
  assert.equal(await revoked(), false);
  // Closed, the tab's PDF is let go.
  await tab.close();
  await page.clock.fastForward('00:10');
  assert.equal(await revoked(), true);
  assert.deepEqual(page.problems, []);
});
