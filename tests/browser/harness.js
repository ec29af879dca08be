// Test harness: a real `pintag serve` on a free loopback port with a temporary database and the
// repository's web/ folder, and Debian's Chromium driven through playwright-core.
//
//   PINTAG_BIN             the pintag binary (ctest passes $<TARGET_FILE:pintag>)
//   PINTAG_CHROMIUM        the browser (default /usr/bin/chromium)
//   PINTAG_SCREENSHOT_DIR  where screenshots go (default: a folder in the temp dir)

import { after, before } from 'node:test';
import { spawn } from 'node:child_process';
import { existsSync } from 'node:fs';
import { mkdir, mkdtemp, rm } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { chromium } from 'playwright-core';

const here = dirname(fileURLToPath(import.meta.url));
export const repoRoot = resolve(here, '..', '..');
export const webDir = join(repoRoot, 'web');
export const screenshotDir = process.env.PINTAG_SCREENSHOT_DIR || join(tmpdir(), 'pintag-browser-screenshots');

function pintagBinary() {
  const candidates = [process.env.PINTAG_BIN, join(repoRoot, 'build', 'server', 'pintag')].filter(Boolean);
  const found = candidates.find((path) => existsSync(path));
  if (!found) throw new Error(`pintag binary not found (set PINTAG_BIN); tried ${candidates.join(', ')}`);
  return found;
}

/**
 * Spawns `pintag <args>` and resolves once it printed its URL (and, when `token` is set, the
 * first-start admin token). Returns {url, adminToken, stop(), stderr()}; stop() also removes
 * `dir` when given.
 */
async function spawnServer(args, { token, dir, timeoutMs }) {
  const child = spawn(pintagBinary(), args, { stdio: ['ignore', 'pipe', 'pipe'] });
  let stdout = '';
  let stderr = '';
  child.stderr.on('data', (chunk) => { stderr += chunk; });
  const started = await new Promise((resolveStart, rejectStart) => {
    const timer = setTimeout(() => {
      rejectStart(new Error(`pintag serve did not start in ${timeoutMs} ms\nstdout: ${stdout}\nstderr: ${stderr}`));
    }, timeoutMs);
    child.stdout.on('data', (chunk) => {
      stdout += chunk;
      const url = stdout.match(/PinTag serving (http:\/\/127\.0\.0\.1:\d+)\//);
      const secret = stdout.match(/^\s+(pt_\d+_[A-Za-z0-9_-]+)\s*$/m);
      if (url && (secret || !token)) {
        clearTimeout(timer);
        resolveStart({ url: url[1], adminToken: secret ? secret[1] : undefined });
      }
    });
    child.on('exit', (code, signal) => {
      clearTimeout(timer);
      rejectStart(new Error(`pintag serve exited (${code ?? signal}) before it was ready\nstdout: ${stdout}\nstderr: ${stderr}`));
    });
  });
  const exited = new Promise((done) => child.on('exit', done));
  return {
    ...started,
    stderr: () => stderr,
    async stop() {
      if (child.exitCode === null && child.signalCode === null) {
        child.kill('SIGTERM');
        const killer = setTimeout(() => child.kill('SIGKILL'), 5000);
        await exited;
        clearTimeout(killer);
      }
      if (dir) await rm(dir, { recursive: true, force: true });
    },
  };
}

/**
 * Starts `pintag serve --port 0` on a fresh database, with `args` added (limits, say); resolves
 * once it printed its URL and the first-start admin token. Returns {url, adminToken, db, stop(),
 * stderr()}.
 */
export async function startServer({ timeoutMs = 30_000, args = [] } = {}) {
  const dir = await mkdtemp(join(tmpdir(), 'pintag-browser-'));
  const db = join(dir, 'pintag.db');
  const server = await spawnServer(
    ['serve', '--db', db, '--port', '0', '--bind', '127.0.0.1', '--web', webDir, ...args],
    { token: true, dir, timeoutMs });
  return { ...server, db };
}

/**
 * A read-only replica of `primary` (docs/SCALING.md): a snapshot of its database taken now,
 * served with `--read-only`. Returns {url, stop(), stderr()}.
 */
export async function startReplica(primary, { timeoutMs = 30_000 } = {}) {
  const dir = await mkdtemp(join(tmpdir(), 'pintag-browser-replica-'));
  const snapshot = join(dir, 'snapshot.db');
  await new Promise((done, fail) => {
    const child = spawn(pintagBinary(), ['snapshot', '--db', primary.db, '--out', snapshot], { stdio: 'ignore' });
    child.on('exit', (code) => (code === 0 ? done() : fail(new Error(`pintag snapshot exited ${code}`))));
  });
  return spawnServer(
    ['serve', '--read-only', '--db', snapshot, '--primary', primary.url, '--scan-log', join(dir, 'scans.db'),
      '--port', '0', '--bind', '127.0.0.1', '--web', webDir],
    { token: false, dir, timeoutMs });
}

/** Makes a token of `role` through the API with the admin token; returns its secret. */
export async function createToken(server, role) {
  const response = await fetch(`${server.url}/api/v1/tokens`, {
    method: 'POST',
    headers: { Authorization: `Bearer ${server.adminToken}`, 'Content-Type': 'application/json' },
    body: JSON.stringify({ role, label: `browser test ${role}` }),
  });
  if (response.status !== 201) throw new Error(`token create: HTTP ${response.status} ${await response.text()}`);
  return (await response.json()).secret;
}

/** Launches headless Chromium (Debian's; Playwright gives it a fresh temporary profile). */
export async function launchBrowser() {
  const executablePath = process.env.PINTAG_CHROMIUM || '/usr/bin/chromium';
  if (!existsSync(executablePath)) {
    throw new Error(`no browser at ${executablePath}: install Debian's chromium (scripts/setup.sh test does)`);
  }
  return chromium.launch({
    executablePath,
    headless: true,
    args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-quic', '--no-first-run',
      '--disable-background-networking', '--disable-component-update', '--disable-sync',
      '--disable-dev-shm-usage'],
  });
}

/**
 * A new page in its own context; page errors, console errors other than the browser's own note
 * of a 4xx/5xx answer, and every server error (5xx) the page received are collected in
 * page.problems so tests can assert there were none. 4xx answers are the pages' expected
 * problems (an unknown pincode) and are asserted by the tests that cause them.
 */
export async function newPage(browser, { viewport = { width: 1280, height: 900 }, ...options } = {}) {
  const context = await browser.newContext({ viewport, acceptDownloads: true, ...options });
  const page = await context.newPage();
  page.problems = [];
  page.on('pageerror', (error) => page.problems.push(`page error: ${error.message}`));
  page.on('console', (message) => {
    if (message.type() === 'error' && !/status of (4|5)\d\d/.test(message.text())) {
      page.problems.push(`console: ${message.text()}`);
    }
  });
  page.on('response', (response) => {
    if (response.status() >= 500) {
      page.problems.push(`server error: ${response.status()} ${response.url()}`);
    }
  });
  page.setDefaultTimeout(15_000);
  return page;
}

/** Saves a full-page screenshot as <screenshotDir>/<name>.png. */
export async function screenshot(page, name) {
  await mkdir(screenshotDir, { recursive: true });
  const path = join(screenshotDir, `${name}.png`);
  await page.screenshot({ path, fullPage: true });
  return path;
}

/**
 * Where each of `parts` is drawn in the element `selector`: the left edge, in CSS pixels, of the
 * first text of the element that holds it (null when none does). For checking the visual order of
 * mixed-direction text, which the DOM's order does not tell.
 */
export function textLefts(page, selector, parts) {
  return page.locator(selector).first().evaluate((root, wanted) => {
    const walker = document.createTreeWalker(root, NodeFilter.SHOW_TEXT);
    const nodes = [];
    for (let node = walker.nextNode(); node; node = walker.nextNode()) nodes.push(node);
    return wanted.map((part) => {
      for (const node of nodes) {
        const at = node.data.indexOf(part);
        if (at < 0) continue;
        const range = document.createRange();
        range.setStart(node, at);
        range.setEnd(node, at + part.length);
        return Math.min(...[...range.getClientRects()].map((box) => box.left));
      }
      return null;
    });
  }, parts);
}

/** Adds `pincode` with `offices` ([{name, district, state}]) through the API with the admin token. */
export async function addPincode(server, pincode, offices) {
  const response = await fetch(`${server.url}/api/v1/pincodes`, {
    method: 'POST',
    headers: { Authorization: `Bearer ${server.adminToken}`, 'Content-Type': 'application/json' },
    body: JSON.stringify({ pincode, offices: offices.map((o) => ({ circle: 'Test', region: 'T', division: 'TD', ...o })) }),
  });
  if (response.status !== 201) throw new Error(`add ${pincode}: HTTP ${response.status} ${await response.text()}`);
  return response.json();
}

/**
 * The server and browser a test file shares: a fresh `pintag serve` and Chromium started before
 * the file's tests and stopped after them, and then `setUp(session)` when given (a file's tokens
 * and inputs: a hook of the file's own may run before these are started). Returns {server,
 * browser}, filled in by then.
 */
export function serverAndBrowser(setUp) {
  const session = {};
  before(async () => {
    session.server = await startServer();
    session.browser = await launchBrowser();
    await setUp?.(session);
  });
  after(async () => {
    await session.browser?.close();
    await session.server?.stop();
  });
  return session;
}
