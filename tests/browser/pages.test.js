// Every page loads from the server without errors, links the others, and labels its fields.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { newPage, screenshot, serverAndBrowser } from './harness.js';

let server;
let browser;

serverAndBrowser(async (session) => {
  ({ server, browser } = session);
});

test('the home page links the three pages and reports the server ready', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/`);
  await page.locator('#ready').filter({ hasText: 'Ready' }).waitFor();
  for (const name of ['Dispatch counter', 'Handheld scanner', 'Registry']) {
    assert.equal(await page.getByRole('link', { name: new RegExp(name) }).count() >= 1, true, name);
  }
  await page.getByRole('link', { name: /Dispatch counter/ }).click();
  await page.waitForURL(/counter\.html$/);
  await page.goto(`${server.url}/`);
  await screenshot(page, 'home');
  assert.deepEqual(page.problems, []);
});

for (const name of ['counter', 'scanner', 'registry']) {
  test(`${name}.html loads cleanly and every form field has a label`, async () => {
    const page = await newPage(browser);
    const failed = [];
    page.on('response', (r) => { if (r.status() >= 400) failed.push(`${r.status()} ${r.url()}`); });
    await page.goto(`${server.url}/${name}.html`);
    await page.waitForLoadState('networkidle');
    assert.deepEqual(failed, []);
    const unlabelled = await page.evaluate(() => [...document.querySelectorAll('input, select, textarea')]
      .filter((e) => e.type !== 'hidden' && !(e.labels && e.labels.length) && !e.getAttribute('aria-label'))
      .map((e) => e.id || e.name));
    assert.deepEqual(unlabelled, []);
    assert.equal(await page.locator('nav a[aria-current="page"]').getAttribute('href'), `${name}.html`);
    assert.deepEqual(page.problems, []);
  });
}

// The pages act with the token typed into them, and retiring cannot be undone: a page of another
// site that framed the registry could lead an admin's click onto a button it hides.
test('another site cannot frame the pages; the server\'s own pages still can', async () => {
  // The registry framed by a page at `host`; whether the frame drew it.
  const drawnInAFrameOf = async (host) => {
    const page = await newPage(browser);
    await page.goto(`${host}/index.html`);
    await page.evaluate((src) => new Promise((resolve) => {
      const frame = document.createElement('iframe');
      frame.src = src;
      frame.onload = resolve;
      document.body.appendChild(frame);
    }), `${server.url}/registry.html`);
    const frame = page.frames().find((f) => f !== page.mainFrame());
    assert.ok(frame, 'the frame was made');
    return (await frame.locator('#retire').count()) === 1;
  };
  // localhost and 127.0.0.1 are two origins: a page of localhost stands for another site.
  assert.equal(await drawnInAFrameOf(server.url.replace('127.0.0.1', 'localhost')), false);
  assert.equal(await drawnInAFrameOf(server.url), true);
});

// Text that reaches a page (an office name from an imported file, a bin) must not run: the pages'
// policy lets only the server's own script and style files run. A page that itself broke the
// policy would log the violation as a console error, which every test's page.problems catches.
test('a page runs no inline script or style attribute, and says so in its console', async () => {
  for (const name of ['index', 'counter', 'scanner', 'registry']) {
    const page = await newPage(browser);
    await page.goto(`${server.url}/${name}.html`);
    await page.waitForLoadState('networkidle');
    assert.deepEqual(page.problems, [], `${name}.html loads within its own policy`);
    const ran = await page.evaluate(async () => {
      const script = document.createElement('script');
      script.textContent = 'window.injectedRan = true;';
      document.body.append(script);
      const marked = document.createElement('p');
      marked.setAttribute('style', 'color: rgb(1, 2, 3)');
      marked.textContent = 'x';
      document.body.append(marked);
      await new Promise((resolve) => setTimeout(resolve, 100));
      return { script: window.injectedRan === true, style: getComputedStyle(marked).color === 'rgb(1, 2, 3)' };
    });
    assert.deepEqual(ran, { script: false, style: false }, name);
    assert.ok(page.problems.some((p) => /Content Security Policy/.test(p)), `${name}: ${page.problems}`);
    await page.context().close();
  }
});
