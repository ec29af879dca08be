// Test harness: a real `pintag serve` on a free loopback port with a temporary database and the
// repository's web/ folder, and Debian's Chromium driven through playwright-core.
//
//   PINTAG_BIN             the pintag binary (ctest passes $<TARGET_FILE:pintag>)
//   PINTAG_CHROMIUM        the browser (default /usr/bin/chromium)
//   PINTAG_SCREENSHOT_DIR  where screenshots go (default: a folder in the temp dir)

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
 * Starts `pintag serve --port 0` on a fresh database; resolves once it printed its URL and the
 * first-start admin token. Returns {url, adminToken, stop(), stderr()}.
 */
export async function startServer({ timeoutMs = 30_000 } = {}) {
  const dir = await mkdtemp(join(tmpdir(), 'pintag-browser-'));
  const child = spawn(pintagBinary(),
    ['serve', '--db', join(dir, 'pintag.db'), '--port', '0', '--bind', '127.0.0.1', '--web', webDir],
    { stdio: ['ignore', 'pipe', 'pipe'] });
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
      const token = stdout.match(/^\s+(pt_\d+_[A-Za-z0-9_-]+)\s*$/m);
      if (url && token) {
        clearTimeout(timer);
        resolveStart({ url: url[1], adminToken: token[1] });
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
      await rm(dir, { recursive: true, force: true });
    },
  };
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
