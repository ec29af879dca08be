// Scanner: a label photo is read with one upload (pincode, office, bin, outline); wrong token and
// non-image fail clearly.
import assert from 'node:assert/strict';
import { execFile } from 'node:child_process';
import { mkdtemp, readFile, rm, writeFile } from 'node:fs/promises';
import { tmpdir } from 'node:os';
import { basename, dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import { promisify } from 'node:util';
import { after, test } from 'node:test';
import { createToken, newPage, screenshot, serverAndBrowser, startServer } from './harness.js';

let server;
let browser;
let scannerToken;
let counterToken;
let dir;
let labelPng;

serverAndBrowser(async (session) => {
  ({ server, browser } = session);
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
  if (dir) await rm(dir, { recursive: true, force: true });
});

test('scanner reads the tag on a label photo and shows the outlined photo', async () => {
  const page = await newPage(browser, { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(`${server.url}/scanner.html`);
  // No capture attribute: a phone then offers its camera and its gallery, as the page promises
  // ("Take or choose a photo"); with capture it opens only the camera.
  assert.equal(await page.locator('#photo').getAttribute('capture'), null);
  await page.locator('#token').fill(scannerToken);
  const uploads = [];
  page.on('request', (request) => {
    if (request.url().includes('/api/v1/detect')) uploads.push(`${request.method()} ${request.url()}`);
  });
  await page.locator('#photo').setInputFiles(labelPng);
  const card = page.locator('.tag-card[data-pincode="110001"]');
  await card.waitFor();
  const text = await card.textContent();
  assert.match(text, /110001/);
  assert.match(text, /Bengali Market/);
  assert.match(text, /Central Delhi/);
  assert.match(text, /Bin11/);
  assert.match(text, /Distance\d+\.\d\d m/);
  // The bin, which the person holding the parcel acts on, is as large as the pincode and beside
  // it on a phone (it was a small chip in the fourth row).
  const size = (selector) => card.locator(selector).evaluate((node) => getComputedStyle(node).fontSize);
  assert.equal(await size('header .bin'), await size('.big-pin'));
  const [pinBox, binBox] = [await card.locator('.big-pin').boundingBox(), await card.locator('header .bin').boundingBox()];
  assert.ok(binBox.y < pinBox.y + pinBox.height && binBox.x > pinBox.x + pinBox.width, JSON.stringify({ pinBox, binBox }));
  assert.match(await page.locator('#summary').textContent(), /1 tag read/);
  // The chosen photo is named in the box that chose it (the file input itself is hidden).
  assert.equal(await page.locator('#photo-name').textContent(), `Chosen: ${basename(labelPng)}`);
  await page.locator('#scan-photo[data-outlined="1"]').waitFor();
  await page.waitForFunction(() => document.getElementById('scan-photo').naturalWidth > 0);
  assert.match(await page.locator('#scan-photo').getAttribute('alt'), /outlined: 110001/);
  // The outline is drawn from the answer's corners: it must sit on the tag in the picture, i.e.
  // inside the photo and around its dark square (the tag is the darkest thing on a label).
  const outline = await outlineOnPicture(page, '110001');
  assert.equal(outline.groups, 1);
  assert.ok(outline.withinPicture, JSON.stringify(outline));
  assert.ok(outline.size > 0.2 && outline.size < 1, JSON.stringify(outline));
  // just inside the outline's left edge (black square) and just outside it (quiet zone)
  assert.ok(outline.inside[0] < 80 && outline.outside[0] > 170, JSON.stringify(outline));
  assert.equal(uploads.length, 1, `one upload per scan, got ${uploads.join(', ')}`);
  assert.match(uploads[0], /^POST /);
  // The server saw one photo too (the handler counts it before it answers).
  const metrics = await (await fetch(`${server.url}/metrics`)).text();
  assert.match(metrics, /^pintag_scans_total 1$/m);
  // On a phone the answer is below the form: the page scrolls to it.
  const summary = await page.locator('#summary').boundingBox();
  // Within a pixel: scrolled to, the top lands on a fraction of a pixel by the fonts' metrics.
  assert.ok(summary.y > -1 && summary.y + summary.height <= 845, JSON.stringify(summary));
  await screenshot(page, 'scanner-phone');

  // A next photo that cannot be read (no token now) leaves nothing of this scan on screen.
  await page.locator('#token-forget').click();
  await page.locator('#photo').setInputFiles(join(dir, 'notes.txt'));  // another file: a change
  await page.locator('#scan-msg [role="alert"]').filter({ hasText: 'No scanner token' }).waitFor();
  assert.equal(await page.locator('.tag-card').count(), 0);
  assert.doesNotMatch(await page.locator('#summary').textContent(), /tag/);
  assert.equal(await page.locator('#photo-figure').isHidden(), true);

  // The photo refused for want of a token is read as soon as one is pasted: choosing the same
  // file again fires no change, and the "Read tags" button is below the fold.
  await page.locator('#photo').setInputFiles(labelPng);
  await page.locator('#scan-msg [role="alert"]').filter({ hasText: 'No scanner token' }).waitFor();
  for (const part of [scannerToken.slice(0, 10), scannerToken.slice(0, -3)]) {  // typed: not yet
    await page.locator('#token').fill(part);
    await page.waitForTimeout(300);
    assert.equal(await page.locator('.tag-card').count(), 0);
    assert.equal(await page.locator('#scan-msg [role="alert"]').filter({ hasText: 'No scanner token' }).count(), 1);
  }
  await page.locator('#token').fill(scannerToken);
  await page.locator('.tag-card[data-pincode="110001"]').waitFor();
  assert.equal(await page.locator('#scan-msg [role="alert"]').count(), 0);
  assert.deepEqual(page.problems, []);
});

test('the photo box shows the keyboard focus, as every other control does', async () => {
  const page = await newPage(browser);
  await page.goto(`${server.url}/scanner.html`);
  const outline = () => page.locator('label.drop').evaluate((box) => getComputedStyle(box).outlineStyle);
  assert.equal(await outline(), 'none');
  // Tab from the field before the hidden file input lands on it.
  await page.locator('#token').focus();
  for (let i = 0; i < 6 && await page.evaluate(() => document.activeElement?.id) !== 'photo'; ++i) {
    await page.keyboard.press('Tab');
  }
  assert.equal(await page.evaluate(() => document.activeElement?.id), 'photo');
  assert.equal(await outline(), 'solid');
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
  // The summary says what failed: the token's role, not the photo.
  assert.match(await page.locator('#summary').textContent(), /^Not read: this token may not read photos/);

  await page.locator('#token').fill('pt_999_notarealtokennotarealtokennotarealtokenxx');
  await page.locator('#photo').setInputFiles(join(dir, 'notes.txt'));
  await alert.filter({ hasText: 'HTTP 401' }).waitFor();
  assert.equal(await page.locator('#summary').textContent(), 'Not read: the scanner token was not accepted.');
});

// A file committed as a seed of the image fuzz target.
const corpusFile = (name) => join(dirname(fileURLToPath(import.meta.url)), '../../fuzz/corpus/image_detect', name);

// A new scanner page, the scanner token given, reading `file`.
async function scannerReading(file) {
  const page = await newPage(browser);
  await page.goto(`${server.url}/scanner.html`);
  await page.locator('#token').fill(scannerToken);
  await page.locator('#photo').setInputFiles(file);
  return page;
}

// Where the outline of `pincode`'s tag lies on the picture shown: whether it is inside the
// picture, its width as a share of it, how many outlines there are, and the luma of the picture
// just inside each edge of the outline (left, right, top, bottom: the black square) and just
// outside it (the quiet zone), 6 % of its side from the edge.
function outlineOnPicture(page, pincode) {
  return page.evaluate((pin) => {
    const img = document.getElementById('scan-photo');
    const box = document.querySelector(`#outlines g[data-pincode="${pin}"] polygon`).getBoundingClientRect();
    const frame = img.getBoundingClientRect();
    const canvas = document.createElement('canvas');
    canvas.width = img.naturalWidth;
    canvas.height = img.naturalHeight;
    const context = canvas.getContext('2d');
    context.drawImage(img, 0, 0);
    const luma = (x, y) => {
      const px = Math.round((x - frame.left) * img.naturalWidth / frame.width);
      const py = Math.round((y - frame.top) * img.naturalHeight / frame.height);
      const [r, g, b] = context.getImageData(px, py, 1, 1).data;
      return 0.2126 * r + 0.7152 * g + 0.0722 * b;
    };
    const cx = box.left + box.width / 2;
    const cy = box.top + box.height / 2;
    const dx = box.width * 0.06;
    const dy = box.height * 0.06;
    return {
      withinPicture: box.left >= frame.left - 1 && box.right <= frame.right + 1
        && box.top >= frame.top - 1 && box.bottom <= frame.bottom + 1,
      size: box.width / frame.width,
      groups: document.querySelectorAll('#outlines g').length,
      inside: [luma(box.left + dx, cy), luma(box.right - dx, cy), luma(cx, box.top + dy), luma(cx, box.bottom - dy)],
      outside: [luma(box.left - dx, cy), luma(box.right + dx, cy), luma(cx, box.top - dy), luma(cx, box.bottom + dy)],
    };
  }, pincode);
}

test('a photo without colour is answered with what to change, not the general advice', async () => {
  // The label as a greyscale PNG, as a camera's black-and-white mode would save it.
  const grey = join(dir, 'label-110001-grey.png');
  await promisify(execFile)('oiiotool', [labelPng, '--chsum:weight=0.2126,0.7152,0.0722', '-o', grey]);
  const page = await scannerReading(grey);
  const note = page.locator('#tags .alert-info');
  await note.waitFor();
  assert.match(await note.textContent(), /^No PinTag found: the photo has no colour.*take the photo in colour/);
  assert.doesNotMatch(await note.textContent(), /Hold the camera steady/);
  assert.match(await page.locator('#summary').textContent(), /^No tag read/);
  await screenshot(page, 'scanner-no-colour');
  assert.deepEqual(page.problems, []);
});

test('a TIFF the browser cannot draw is still read, and the page says why no photo is shown', async () => {
  // A committed 8-bit RGB TIFF holding one tag (also a seed of the image fuzz target).
  const page = await scannerReading(corpusFile('tag.tif'));
  await page.locator('.tag-card').first().waitFor();
  const summary = page.locator('#summary');
  await summary.filter({ hasText: 'cannot show the photo itself' }).waitFor();
  assert.match(await summary.textContent(), /^1 tag read/);
  assert.equal((await summary.textContent()).match(/cannot show the photo/g).length, 1);
  assert.equal(await page.locator('#photo-figure').isHidden(), true);  // no broken picture
  await screenshot(page, 'scanner-tiff');
  assert.deepEqual(page.problems, []);
  // Turned by its EXIF orientation, a square TIFF leaves no size to judge by: the page must not
  // look for the tags on a picture it could not draw.
  const turned = join(dir, 'label-square-exif6.tif');
  await promisify(execFile)('oiiotool', [labelPng, '--crop', '0,0,899,899', '--fullpixels',
    '--attrib', 'Orientation', '6', '-o', turned]);
  const turnedPage = await scannerReading(turned);
  await turnedPage.locator('#summary').filter({ hasText: /^1 tag read.*cannot show the photo itself/ }).waitFor();
  assert.deepEqual(turnedPage.problems, []);
});

test('the outline sits on the tag of a WebP whose EXIF orientation the browser does not apply', async () => {
  // A committed 450 × 800 WebP holding the tag of 110001, stored turned a quarter with EXIF
  // Orientation 6 (also a seed of the image fuzz target). The server reads it upright
  // (800 × 450); Chromium shows a WebP as stored, so the page must place the corners itself.
  const page = await scannerReading(corpusFile('tag-exif6.webp'));
  await page.locator('#scan-photo[data-outlined="1"]').waitFor();
  assert.match(await page.locator('#summary').textContent(), /^1 tag read.*photo 800 × 450/);
  // Every edge of the outline lies on the black square's edge: inside dark, outside light.
  const outline = await outlineOnPicture(page, '110001');
  const shown = JSON.stringify(outline);
  for (const value of outline.inside) assert.ok(value < 80, shown);
  for (const value of outline.outside) assert.ok(value > 170, shown);
  await screenshot(page, 'scanner-webp-exif6');
  assert.deepEqual(page.problems, []);
});

// A WebP saved with an EXIF chunk holding `tiff` (a TIFF-structured EXIF block), from a plain
// WebP (RIFF, WEBP, one image chunk) of `width` × `height`: the extended layout, VP8X with the
// EXIF flag, the image chunk, then EXIF.
function webpWithExif(plain, width, height, tiff) {
  const chunk = (tag, payload) => {
    const head = Buffer.alloc(8);
    head.write(tag, 0, 'latin1');
    head.writeUInt32LE(payload.length, 4);
    return Buffer.concat([head, payload, Buffer.alloc(payload.length % 2)]);
  };
  const vp8x = Buffer.alloc(10);
  vp8x[0] = 0x08;
  vp8x.writeUIntLE(width - 1, 4, 3);
  vp8x.writeUIntLE(height - 1, 7, 3);
  const body = Buffer.concat([Buffer.from('WEBP', 'latin1'), chunk('VP8X', vp8x), plain.subarray(12), chunk('EXIF', tiff)]);
  const riff = Buffer.alloc(8);
  riff.write('RIFF', 0, 'latin1');
  riff.writeUInt32LE(body.length, 4);
  return Buffer.concat([riff, body]);
}

// A TIFF-structured EXIF block of one directory, IFD0, holding SHORT entries `[[tag, value], …]`,
// and, when `exifShorts` are given, a pointer to an EXIF directory holding those.
function tiffBlock({ bigEndian = false, shorts = [], exifShorts = null }) {
  const ifd0 = [...shorts];
  const ifd0Bytes = 2 + 12 * (ifd0.length + (exifShorts ? 1 : 0)) + 4;
  const exifAt = 8 + ifd0Bytes;
  const tiff = Buffer.alloc(exifAt + (exifShorts ? 2 + 12 * exifShorts.length + 4 : 0));
  const u16 = (value, at) => (bigEndian ? tiff.writeUInt16BE(value, at) : tiff.writeUInt16LE(value, at));
  const u32 = (value, at) => (bigEndian ? tiff.writeUInt32BE(value, at) : tiff.writeUInt32LE(value, at));
  tiff.write(bigEndian ? 'MM' : 'II', 0, 'latin1');
  u16(42, 2);
  u32(8, 4);
  const directory = (at, entries, pointer) => {
    u16(entries.length + (pointer ? 1 : 0), at);
    entries.forEach(([tag, value], i) => {
      u16(tag, at + 2 + 12 * i);
      u16(3, at + 4 + 12 * i);  // SHORT
      u32(1, at + 6 + 12 * i);
      u16(value, at + 10 + 12 * i);
    });
    if (pointer) {
      const entry = at + 2 + 12 * entries.length;
      u16(0x8769, entry);
      u16(4, entry + 2);  // LONG
      u32(1, entry + 4);
      u32(pointer, entry + 8);
    }
  };
  directory(8, ifd0, exifShorts ? exifAt : 0);
  if (exifShorts) directory(exifAt, exifShorts, 0);
  return tiff;
}

function webpWithOrientation(plain, width, height, o) {
  return webpWithExif(plain, width, height, tiffBlock({ shorts: [[0x0112, o]] }));
}

// The outline of 110001's tag lies on the black square shown: inside dark, outside light.
async function expectOutlineOnTheTag(page, what) {
  await page.locator('#scan-photo[data-outlined="1"]').waitFor();
  const outline = await outlineOnPicture(page, '110001');
  const shown = `${what}: ${JSON.stringify(outline)}`;
  for (const value of outline.inside) assert.ok(value < 80, shown);
  for (const value of outline.outside) assert.ok(value > 170, shown);
}

test('the outline sits on the tag whatever the orientation, when the size cannot tell', async () => {
  // The photo's size tells only when the orientation turns a photo that is not square a quarter:
  // for a half turn or a mirror (2–4), and for a square photo, the page judged wrongly and drew
  // the outline beside the tag of a WebP, which Chromium shows as stored.
  const committed = await readFile(corpusFile('tag-exif6.webp'));
  const halfTurn = Buffer.from(committed);
  const entry = halfTurn.indexOf(Buffer.from([0x01, 0x12, 0x00, 0x03, 0, 0, 0, 1]));
  assert.ok(entry > 0, 'the committed WebP holds a big-endian Orientation entry');
  halfTurn[entry + 9] = 3;
  const halfTurnFile = join(dir, 'tag-exif3.webp');
  await writeFile(halfTurnFile, halfTurn);
  let page = await scannerReading(halfTurnFile);
  await expectOutlineOnTheTag(page, 'WebP, orientation 3');
  await screenshot(page, 'scanner-webp-exif3');

  const plainSquare = join(dir, 'label-square.webp');
  await promisify(execFile)('oiiotool', [labelPng, '--crop', '0,0,899,899', '--fullpixels', '-o', plainSquare]);
  const squareFile = join(dir, 'label-square-exif6.webp');
  await writeFile(squareFile, webpWithOrientation(await readFile(plainSquare), 900, 900, 6));
  page = await scannerReading(squareFile);
  await expectOutlineOnTheTag(page, 'square WebP, orientation 6');
  assert.match(await page.locator('#summary').textContent(), /photo 900 × 900/);

  // A JPEG's orientation the browser applies: the outline goes on the upright picture.
  const jpeg = join(dir, 'label-exif3.jpg');
  await promisify(execFile)('oiiotool', [labelPng, '--attrib', 'Orientation', '3', '-o', jpeg]);
  page = await scannerReading(jpeg);
  await expectOutlineOnTheTag(page, 'JPEG, orientation 3');
  assert.deepEqual(page.problems, []);
});

// The TIFF-structured EXIF block of a JPEG (its APP1 "Exif\0\0" segment).
function jpegExif(jpeg) {
  for (let at = 2; at + 4 <= jpeg.length;) {
    const length = jpeg.readUInt16BE(at + 2);
    if (jpeg[at + 1] === 0xe1 && jpeg.toString('latin1', at + 4, at + 10) === 'Exif\0\0') {
      return jpeg.subarray(at + 10, at + 2 + length);
    }
    at += 2 + length;
  }
  throw new Error('no EXIF in the JPEG');
}

// A PNG with an eXIf chunk holding `tiff`, before its first IDAT.
function pngWithExif(png, tiff) {
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc32 = (bytes) => {
    let c = 0xffffffff;
    for (const b of bytes) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const typeAndData = Buffer.concat([Buffer.from('eXIf', 'latin1'), tiff]);
  const chunk = Buffer.alloc(12 + tiff.length);
  chunk.writeUInt32BE(tiff.length, 0);
  typeAndData.copy(chunk, 4);
  chunk.writeUInt32BE(crc32(typeAndData), 8 + tiff.length);
  const idat = png.indexOf(Buffer.from('IDAT', 'latin1')) - 4;
  return Buffer.concat([png.subarray(0, idat), chunk, png.subarray(idat)]);
}

test('the page reads a photo\'s lens from its EXIF as the server does', async () => {
  // The scanner sends the lens of a photo it makes smaller (web/exif.js). Each photo here is read
  // whole by the server, which takes the lens from the file's EXIF, and by the page's reader at
  // the photo's own size: both must find the same focal length, or both none.
  const oiio = (args) => promisify(execFile)('oiiotool', args);
  const path = (name) => join(dir, name);
  await oiio([labelPng, '--attrib', 'Exif:FocalLengthIn35mmFilm', '52', '-o', path('lens-35mm.jpg')]);
  // 4.25 mm over 2000 pixels a centimetre: 850 px, no 35 mm-equivalent given.
  await oiio([labelPng, '--attrib:type=float', 'Exif:FocalLength', '4.25', '--attrib:type=float',
    'Exif:FocalPlaneXResolution', '2000', '--attrib:type=int', 'Exif:FocalPlaneResolutionUnit', '3',
    '-o', path('lens-plane.jpg')]);
  // A resolution unit of 0, which the server reads as inches, as when it is missing.
  await oiio([labelPng, '--attrib:type=float', 'Exif:FocalLength', '4.25', '--attrib:type=float',
    'Exif:FocalPlaneXResolution', '2000', '--attrib:type=int', 'Exif:FocalPlaneResolutionUnit', '0',
    '-o', path('lens-unit-0.jpg')]);
  // What some writers put for "unknown".
  await oiio([labelPng, '--attrib', 'Exif:FocalLengthIn35mmFilm', '65535', '-o', path('lens-unknown.jpg')]);
  await oiio([labelPng, '-o', path('label.webp')]);
  const png = await readFile(labelPng);
  const [width, height] = [png.readUInt32BE(16), png.readUInt32BE(20)];
  const plainWebp = await readFile(path('label.webp'));
  await writeFile(path('lens-plane.png'), pngWithExif(png, jpegExif(await readFile(path('lens-plane.jpg')))));
  await writeFile(path('lens-35mm.webp'), webpWithExif(plainWebp, width, height,
    jpegExif(await readFile(path('lens-35mm.jpg')))));
  await writeFile(path('lens-35mm-big-endian.webp'), webpWithExif(plainWebp, width, height,
    tiffBlock({ bigEndian: true, shorts: [[0x0112, 1]], exifShorts: [[0xa405, 35]] })));
  // The lens in IFD0 rather than the EXIF directory, where the server's reader takes it too.
  await writeFile(path('lens-in-ifd0.webp'), webpWithExif(plainWebp, width, height,
    tiffBlock({ shorts: [[0xa405, 35]] })));
  // Fill bytes (0xFF) before the EXIF segment, which JPEG allows between segments.
  const lens35 = await readFile(path('lens-35mm.jpg'));
  const app1 = lens35.indexOf(Buffer.from('\xff\xe1', 'latin1'));
  await writeFile(path('lens-fill-bytes.jpg'),
    Buffer.concat([lens35.subarray(0, app1), Buffer.from([0xff, 0xff, 0xff]), lens35.subarray(app1)]));
  // IFD0 says 35 mm and the EXIF directory 0 ("unknown"), or 52 mm: which the server takes.
  await writeFile(path('lens-zero-over-ifd0.webp'), webpWithExif(plainWebp, width, height,
    tiffBlock({ shorts: [[0xa405, 35]], exifShorts: [[0xa405, 0]] })));
  await writeFile(path('lens-both-directories.webp'), webpWithExif(plainWebp, width, height,
    tiffBlock({ shorts: [[0xa405, 35]], exifShorts: [[0xa405, 52]] })));
  // A lens whose directory lies past the block's end: no lens.
  const cut = tiffBlock({ exifShorts: [[0xa405, 35]] });
  await writeFile(path('lens-cut-short.webp'), webpWithExif(plainWebp, width, height, cut.subarray(0, cut.length - 8)));

  const page = await newPage(browser);
  await page.goto(`${server.url}/scanner.html`);
  const expected = {
    'lens-35mm.jpg': 'exif', 'lens-plane.jpg': 'exif', 'lens-unknown.jpg': 'assumed', 'lens-plane.png': 'exif',
    'lens-35mm.webp': 'exif', 'lens-35mm-big-endian.webp': 'exif', 'lens-in-ifd0.webp': 'exif',
    'lens-cut-short.webp': 'assumed', 'lens-fill-bytes.jpg': 'exif', 'lens-unit-0.jpg': 'exif',
    'lens-zero-over-ifd0.webp': 'exif', 'lens-both-directories.webp': 'exif',
    'label.webp': 'assumed',
  };
  for (const [name, source] of Object.entries(expected)) {
    const bytes = await readFile(path(name));
    const upload = new FormData();
    upload.append('image', new Blob([bytes]), name);
    const answer = await (await fetch(`${server.url}/api/v1/detect`, {
      method: 'POST', body: upload, headers: { Authorization: `Bearer ${scannerToken}` },
    })).json();
    assert.equal(answer.tag_count, 1, name);
    assert.equal(answer.intrinsics.source, source, name);
    const pageFocal = await page.evaluate(async ({ base64, w, h }) => {
      const { exifLens, focalPixelsOf } = await import('/exif.js');
      const file = new File([Uint8Array.from(atob(base64), (c) => c.charCodeAt(0))], 'photo');
      return focalPixelsOf(await exifLens(file), w, h, w, h);
    }, { base64: bytes.toString('base64'), w: answer.image.width, h: answer.image.height });
    if (source === 'exif') {
      assert.ok(Math.abs(pageFocal - answer.intrinsics.fx) < 1e-6 * answer.intrinsics.fx,
        `${name}: the page ${pageFocal}, the server ${answer.intrinsics.fx}`);
    } else {
      assert.equal(pageFocal, null, name);
    }
  }
  assert.deepEqual(page.problems, []);
});

test('the captions of many tags in one photo stay apart', async () => {
  // A hundred tags of 64 px in a 10 × 10 grid: captions sized by the photo piled over each other.
  const response = await fetch(`${server.url}/api/v1/tags/110001.png?px=64`,
    { headers: { Authorization: `Bearer ${counterToken}` } });
  assert.equal(response.status, 200);
  const tag = join(dir, 'tag-110001.png');
  await writeFile(tag, Buffer.from(await response.arrayBuffer()));
  const grid = join(dir, 'grid.png');
  await promisify(execFile)('oiiotool', [...Array(100).fill(tag), '--mosaic:pad=8', '10x10', '-o', grid]);
  const page = await scannerReading(grid);
  await page.locator('#scan-photo[data-outlined="1"]').waitFor();
  assert.match(await page.locator('#summary').textContent(), /^100 tags read/);
  const boxes = await page.locator('#outlines text').evaluateAll((texts) => texts.map((t) => {
    const b = t.getBoundingClientRect();
    return [b.left, b.top, b.right, b.bottom];
  }));
  assert.equal(boxes.length, 100);
  for (let i = 0; i < boxes.length; ++i) {
    for (let j = i + 1; j < boxes.length; ++j) {
      const [a, b] = [boxes[i], boxes[j]];
      const overlap = a[0] < b[2] && b[0] < a[2] && a[1] < b[3] && b[1] < a[3];
      assert.ok(!overlap, `captions ${i} and ${j} overlap: ${JSON.stringify([a, b])}`);
    }
  }
  await screenshot(page, 'scanner-many-tags');
  assert.deepEqual(page.problems, []);
});

test('a tag whose mirror image is another pincode\'s says so on its card, mirrored or not', async () => {
  // The format has no handedness: 609405's tag flipped left to right is exactly another
  // pincode's tag (docs/FORMAT.md, "Mirror images"). The flip is made by the browser's canvas.
  const response = await fetch(`${server.url}/api/v1/labels/609405.png?dpi=150`,
    { headers: { Authorization: `Bearer ${counterToken}` } });
  assert.equal(response.status, 200);
  const upright = join(dir, 'label-609405.png');
  await writeFile(upright, Buffer.from(await response.arrayBuffer()));
  const page = await scannerReading(upright);
  const card = page.locator('.tag-card[data-pincode="609405"]');
  await card.waitFor();
  const other = await card.getAttribute('data-mirror-pincode');
  assert.match(other, /^\d{6}$/);
  assert.notEqual(other, '609405');
  assert.match(await card.textContent(), new RegExp(`mirrored photo.*reads as ${other}`));

  const flippedBase64 = await page.evaluate(async ([url, token]) => {
    const blob = await (await fetch(url, { headers: { Authorization: `Bearer ${token}` } })).blob();
    const bitmap = await createImageBitmap(blob);
    const canvas = new OffscreenCanvas(bitmap.width, bitmap.height);
    const context = canvas.getContext('2d');
    context.translate(bitmap.width, 0);
    context.scale(-1, 1);
    context.drawImage(bitmap, 0, 0);
    const bytes = new Uint8Array(await (await canvas.convertToBlob({ type: 'image/png' })).arrayBuffer());
    let text = '';
    for (const byte of bytes) text += String.fromCharCode(byte);
    return btoa(text);
  }, [`${server.url}/api/v1/labels/609405.png?dpi=150`, counterToken]);
  const flipped = join(dir, 'label-609405-mirrored.png');
  await writeFile(flipped, Buffer.from(flippedBase64, 'base64'));
  await page.locator('#photo').setInputFiles(flipped);
  const mirroredCard = page.locator(`.tag-card[data-pincode="${other}"]`);
  await mirroredCard.waitFor();
  assert.equal(await mirroredCard.getAttribute('data-mirror-pincode'), '609405');
  assert.match(await mirroredCard.textContent(), /mirrored photo.*reads as 609405/);
  await screenshot(page, 'scanner-mirror-pair');
  assert.deepEqual(page.problems, []);
});

test('a change of sort plan or label size reads the photo again, and the summary names the plan', async () => {
  const put = await fetch(`${server.url}/api/v1/sortplans/hub`, {
    method: 'PUT',
    headers: { Authorization: `Bearer ${server.adminToken}`, 'Content-Type': 'text/csv' },
    body: 'prefix,bin\n*,manual\n11,delhi\n110001,parliament\n',
  });
  assert.ok([200, 201].includes(put.status), `PUT hub: ${put.status}`);
  const uploads = [];
  const page = await newPage(browser);
  page.on('request', (request) => {
    if (request.url().includes('/api/v1/detect')) uploads.push(new URL(request.url()).searchParams);
  });
  await page.goto(`${server.url}/scanner.html`);
  await page.locator('#plan option[value="hub"]').waitFor({ state: 'attached' });
  await page.locator('#token').fill(scannerToken);
  await page.locator('#photo').setInputFiles(labelPng);
  const bin = page.locator('.tag-card[data-pincode="110001"] .bin');
  await bin.waitFor();
  assert.equal(await bin.textContent(), '11');
  const summary = page.locator('#summary');
  assert.match(await summary.textContent(), /^1 tag read in \d+ ms · photo \d+ × \d+ · plan default/);

  await page.locator('#plan').selectOption('hub');
  await page.locator('.tag-card[data-pincode="110001"] .bin').filter({ hasText: 'parliament' }).waitFor();
  await summary.filter({ hasText: /plan hub/ }).waitFor();
  assert.equal(await page.locator('#summary bdi').textContent(), 'hub');
  assert.equal(uploads.length, 2);
  assert.equal(uploads[1].get('plan'), 'hub');
  await page.locator('#scan-photo[data-outlined="1"]').waitFor();
  await screenshot(page, 'scanner-plan-hub');

  // The distances follow the tag's size: read again with the 4 × 6 in label's (and the plan).
  await page.locator('#label-size').selectOption({ label: '4 × 6 in' });
  // The outline goes as the new reading starts and comes back when it is drawn.
  await page.locator('#scan-photo[data-outlined="1"]').waitFor();
  assert.equal(uploads.length, 3);
  assert.equal(uploads[2].get('tag_size_mm'), '58.889');
  assert.equal(uploads[2].get('plan'), 'hub');

  // Without a token, no bin of the plan before stays on screen as if it were this plan's.
  await page.locator('#token-forget').click();
  await page.locator('#plan').selectOption('default');
  await summary.filter({ hasText: 'paste a scanner token' }).waitFor();
  assert.equal(await page.locator('.tag-card').count(), 0);
  assert.equal(await page.locator('#photo-figure').isHidden(), true);
  assert.equal(uploads.length, 3);

  // The station keeps its plan and label size over a reload (both reset to the defaults before),
  // and a photo chosen before the plan list has come is read once, with the kept plan.
  await page.locator('#plan').selectOption('hub');
  await page.locator('#token').fill(scannerToken);
  let releasePlans;
  const plansHeld = new Promise((resolve) => { releasePlans = resolve; });
  await page.route('**/api/v1/sortplans', async (route) => {
    await plansHeld;
    await route.continue();
  });
  await page.reload();
  await page.locator('#photo').setInputFiles(labelPng);
  await page.waitForTimeout(300);
  assert.equal(uploads.length, 3, 'no read before the plan list has come');
  releasePlans();
  await page.locator('.tag-card[data-pincode="110001"] .bin').filter({ hasText: 'parliament' }).waitFor();
  assert.equal(await page.locator('#plan').inputValue(), 'hub');
  assert.equal(await page.locator('#label-size').inputValue(), '58.889');
  await page.waitForTimeout(300);
  assert.equal(uploads.length, 4);
  assert.equal(uploads[3].get('plan'), 'hub');
  await page.unroute('**/api/v1/sortplans');

  // A kept plan the server no longer has: the default plan is shown, and the kept one forgotten.
  await page.evaluate(() => localStorage.setItem('pintag.scanner.plan', 'gone'));
  await page.reload();
  await page.locator('#plan option[value="hub"]').waitFor({ state: 'attached' });
  await page.waitForFunction(() => document.getElementById('plan').value === 'default');
  await page.waitForFunction(() => localStorage.getItem('pintag.scanner.plan') === null);
  assert.deepEqual(page.problems, []);
});

test('a photo over the server\'s pixel or body limit is read made smaller, and the page says so', async () => {
  // Limits far below the defaults, so that small files go over them: 1 MP and half a MiB.
  const limited = await startServer({ args: ['--max-pixels', '1000000', '--max-body-mb', '0.5'] });
  try {
    const token = await createToken(limited, 'scanner');
    const read = async (file) => {
      const page = await newPage(browser);
      const uploads = [];
      const answers = [];
      page.on('request', (request) => {
        if (request.url().includes('/api/v1/detect')) uploads.push(request.method());
      });
      page.on('response', async (response) => {
        if (response.url().includes('/api/v1/detect') && response.ok()) {
          answers.push({ url: new URL(response.url()), json: await response.json() });
        }
      });
      await page.goto(`${limited.url}/scanner.html`);
      await page.locator('#token').fill(token);
      await page.locator('#photo').setInputFiles(file);
      await page.locator('#summary').filter({ hasText: /read in/ }).waitFor();
      return { page, uploads, answers };
    };
    const photoSize = async (page) => {
      const [, width, height] = (await page.locator('#summary').textContent()).match(/photo (\d+) × (\d+)/);
      return [Number(width), Number(height)];
    };

    // Over the pixel limit: the label at twice its size, 2.1 MP, as a JPEG turned by its EXIF
    // orientation (6, a quarter turn), well under the body limit, with a phone's lens in its EXIF.
    const big = join(dir, 'label-2x-exif6.jpg');
    await promisify(execFile)('oiiotool', [labelPng, '--resize', '200%', '--attrib', 'Orientation', '6',
      '--attrib', 'Exif:FocalLengthIn35mmFilm', '26', '--quality', '90', '-o', big]);
    const [storedWidth, storedHeight] = (await promisify(execFile)('oiiotool', ['--info', big]))
      .stdout.match(/(\d+) x\s+(\d+)/).slice(1).map(Number);
    assert.ok(storedWidth * storedHeight > 1_000_000, `${storedWidth} x ${storedHeight}`);
    assert.ok((await readFile(big)).length < 500_000);
    let { page, uploads, answers } = await read(big);
    await page.locator('.tag-card[data-pincode="110001"]').waitFor();
    let summary = await page.locator('#summary').textContent();
    assert.match(summary, /^1 tag read/);
    // The smaller photo went without the file's EXIF, but with its lens: the tag is as far away
    // as the server finds it in the photo as chosen (read by a server without the limits).
    assert.doesNotMatch(summary, /approximate/);
    assert.equal(answers.length, 1);
    const [{ url: smallerUrl, json: smallerAnswer }] = answers;
    assert.equal(smallerAnswer.intrinsics.source, 'given');
    const wholeUrl = new URL(`${server.url}/api/v1/detect`);
    for (const name of ['plan', 'tag_size_mm']) wholeUrl.searchParams.set(name, smallerUrl.searchParams.get(name));
    const upload = new FormData();
    upload.append('image', new Blob([await readFile(big)], { type: 'image/jpeg' }), 'whole.jpg');
    const whole = await (await fetch(wholeUrl, {
      method: 'POST', body: upload, headers: { Authorization: `Bearer ${scannerToken}` },
    })).json();
    assert.equal(whole.intrinsics.source, 'exif');
    const [wholeDistance, smallerDistance] = [whole, smallerAnswer].map((a) => a.tags[0].pose.distance_m);
    assert.ok(Math.abs(smallerDistance - wholeDistance) < 0.01 * wholeDistance,
      `made smaller ${smallerDistance} m, as chosen ${wholeDistance} m`);
    const diagonal = (a) => Math.hypot(a.image.width, a.image.height);
    assert.ok(Math.abs(smallerAnswer.intrinsics.fx / whole.intrinsics.fx - diagonal(smallerAnswer) / diagonal(whole)) < 0.01,
      'the focal length scaled with the photo');
    // Drawn upright: the photo's sides swapped by the orientation, as the server's answer has them.
    assert.match(summary, new RegExp(`made smaller to fit the server's limit \\(${storedHeight} × ${storedWidth}, 2\\.\\d MP\\)`));
    assert.match(summary, /set the camera to a lower resolution/);
    let [width, height] = await photoSize(page);
    assert.ok(width * height <= 1_000_000 && width * height > 900_000, `${width} × ${height}`);
    // Drawn by its orientation: the stored portrait label is shown, and read, on its side.
    assert.ok(width > height, `${width} × ${height}, turned`);
    assert.equal(uploads.length, 2, 'the photo as chosen, then made smaller');
    assert.equal(await page.locator('.alert-error').count(), 0);
    // The picture shown is the one read, and the outline sits on its tag.
    await expectOutlineOnTheTag(page, 'a photo made smaller');
    assert.equal(await page.evaluate(() => document.getElementById('scan-photo').naturalWidth), width);
    await screenshot(page, 'scanner-made-smaller');
    assert.deepEqual(page.problems, []);

    // Over the body limit alone: a noisy PNG of 0.9 MP, which no PNG encoder can keep small.
    const noisy = join(dir, 'label-noisy.png');
    await promisify(execFile)('oiiotool', [labelPng, '--resize', '800x1128', '--noise:type=gaussian:stddev=0.04',
      '-o', noisy]);
    assert.ok((await readFile(noisy)).length > 0.5 * 1024 * 1024, 'the PNG is over the body limit');
    ({ page, uploads, answers } = await read(noisy));
    await page.locator('.tag-card[data-pincode="110001"]').waitFor();
    summary = await page.locator('#summary').textContent();
    assert.match(summary, /^1 tag read/);
    // No lens in the file, none sent: the server assumes one, and the page says so.
    assert.match(summary, /distances approximate/);
    assert.equal(answers[0].url.searchParams.get('fx'), null);
    assert.match(summary, /made smaller to fit the server's limit \(800 × 1128, 0\.9 MP\): send the photo as a JPEG/);
    [width, height] = await photoSize(page);
    assert.ok(width <= 800 && height <= 1128, `${width} × ${height}`);
    // The server read the second upload, so it was under the body limit it enforces.
    assert.equal(uploads.length, 2);
    assert.deepEqual(page.problems, []);

    // Over both: the body's limit is refused first and gives no pixel limit, so the JPEG made
    // for it is refused for its pixels, and drawn once more under both limits.
    const noisyBig = join(dir, 'label-noisy-2x.png');
    await promisify(execFile)('oiiotool', [labelPng, '--resize', '200%', '--noise:type=gaussian:stddev=0.04',
      '-o', noisyBig]);
    ({ page, uploads } = await read(noisyBig));
    await page.locator('.tag-card[data-pincode="110001"]').waitFor();
    summary = await page.locator('#summary').textContent();
    assert.match(summary, /^1 tag read/);
    assert.match(summary, /made smaller to fit the server's limit \(\d+ × \d+, 2\.\d MP\): set the camera to a lower resolution/);
    [width, height] = await photoSize(page);
    assert.ok(width * height <= 1_000_000, `${width} × ${height}`);
    assert.equal(uploads.length, 3, 'refused for its length, then for its pixels, then read');
    assert.deepEqual(page.problems, []);

    // A transparent PNG is drawn on white, as the server reads one, not on black.
    const clear = join(dir, 'label-transparent.png');
    await promisify(execFile)('oiiotool', [labelPng, '--resize', '200%', '--ch', 'R,G,B,A=0.0', '-o', clear]);
    ({ page } = await read(clear));
    await page.locator('#scan-photo[data-outlined="1"]').waitFor();
    const corner = await page.evaluate(() => {
      const img = document.getElementById('scan-photo');
      const canvas = document.createElement('canvas');
      canvas.width = img.naturalWidth;
      canvas.height = img.naturalHeight;
      const context = canvas.getContext('2d');
      context.drawImage(img, 0, 0);
      return Array.from(context.getImageData(1, 1, 1, 1).data);
    });
    assert.ok(corner[0] > 240 && corner[1] > 240 && corner[2] > 240, `the corner is ${corner}`);

    // A browser that cannot make so large a canvas (iOS Safari stops at 16.7 MP; here every
    // canvas over 0.5 MP fails): the server's problem is shown, not a script error.
    page = await newPage(browser);
    await page.addInitScript(() => {
      const original = HTMLCanvasElement.prototype.getContext;
      HTMLCanvasElement.prototype.getContext = function getContext(...args) {
        return this.width * this.height > 500_000 ? null : original.apply(this, args);
      };
    });
    await page.goto(`${limited.url}/scanner.html`);
    await page.locator('#token').fill(token);
    await page.locator('#photo').setInputFiles(big);
    let problem = page.locator('#scan-msg [role="alert"]');
    await problem.waitFor();
    assert.match(await problem.textContent(), /Image Too Large.*lower resolution/);
    assert.deepEqual(page.problems, []);

    // A TIFF over the pixel limit cannot be drawn here: the server's problem is shown as it was.
    const bigTiff = join(dir, 'label-2x.tif');
    await promisify(execFile)('oiiotool', [labelPng, '--resize', '200%', '-o', bigTiff]);
    page = await newPage(browser);
    await page.goto(`${limited.url}/scanner.html`);
    await page.locator('#token').fill(token);
    await page.locator('#photo').setInputFiles(bigTiff);
    problem = page.locator('#scan-msg [role="alert"]');
    await problem.waitFor();
    assert.match(await problem.textContent(), /Image Too Large.*lower resolution/);
    assert.equal(await page.locator('.tag-card').count(), 0);
  } finally {
    await limited.stop();
  }
});
