// Scanner: a label photo is read (pincode, office, bin, overlay); wrong token and non-image fail clearly.
import assert from 'node:assert/strict';
import { mkdtemp, rm, writeFile } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, test } from 'node:test';
import { createToken, launchBrowser, newPage, screenshot, startServer } from './harness.js';

let server;
let browser;
let scannerToken;
let counterToken;
let dir;
let labelPng;

before(async () => {
  server = await startServer();
  browser = await launchBrowser();
  scannerToken = await createToken(server, 'scanner');
  counterToken = await createToken(server, 'counter');
  dir = await mkdtemp(join(tmpdir(), 'pintag-scan-'));
  const response = await fetch(`${server.url}/api/v1/labels/110001.png?dpi=150&plan=default`,
    { headers: { Authorization: `Bearer ${counterToken}` } });
  assert.equal(response.status, 200);
  labelPng = join(dir, 'label-110001.png');
  await writeFile(labelPng, Buffer.from(await response.arrayBuffer()));
  await writeFile(join(dir, 'notes.txt'), 'this is not a photo\n');
});
after(async () => {
  await browser?.close();
  await server?.stop();
  if (dir) await rm(dir, { recursive: true, force: true });
});

test('scanner reads the tag on a label photo and shows the outlined photo', async () => {
  const page = await newPage(browser, { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(`${server.url}/scanner.html`);
  assert.equal(await page.locator('#photo').getAttribute('capture'), 'environment');
  await page.locator('#token').fill(scannerToken);
  await page.locator('#photo').setInputFiles(labelPng);
  const card = page.locator('.tag-card[data-pincode="110001"]');
  await card.waitFor();
  const text = await card.textContent();
  assert.match(text, /110001/);
  assert.match(text, /Bengali Market/);
  assert.match(text, /Central Delhi/);
  assert.match(text, /Bin11/);
  assert.match(text, /Distance\d+\.\d\d m/);
  assert.match(await page.locator('#summary').textContent(), /1 tag read/);
  await page.locator('#overlay[data-overlay="1"]').waitFor();
  await page.waitForFunction(() => document.getElementById('overlay').naturalWidth > 0);
  assert.match(await page.locator('#overlay').getAttribute('alt'), /outlined: 110001/);
  await screenshot(page, 'scanner-phone');
  assert.deepEqual(page.problems, []);
});

test('scanner shows the problem for a non-image file and for a token of the wrong role', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/scanner.html`);
  await page.locator('#token').fill(scannerToken);
  await page.locator('#photo').setInputFiles(join(dir, 'notes.txt'));
  const alert = page.locator('#scan-msg [role="alert"]');
  await alert.waitFor();
  assert.match(await alert.textContent(), /Unsupported Image Format/);
  assert.match(await alert.textContent(), /not a JPEG, PNG, TIFF or WebP image/);
  await page.locator('#photo-figure').waitFor({ state: 'hidden' });  // no broken picture
  await screenshot(page, 'scanner-error');

  await page.locator('#token').fill(counterToken);
  await page.locator('#photo').setInputFiles(labelPng);
  await alert.filter({ hasText: 'HTTP 403' }).waitFor();
});
