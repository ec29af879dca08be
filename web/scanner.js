// Handheld scanner: a photo in, every tag's pincode, office, bin and distance out, and the photo
// with the tags outlined. One upload: the outlines are drawn here from the answer's corners, so
// each scan is one detection, one scan-log row and one request in /metrics. (?overlay=inline
// would bring the server's drawing in the same answer, but as the whole photo again in PNG,
// megabytes per scan over a phone's connection, where the corners are a few hundred bytes.)
import {
  api, query, el, show, problemBox, badge, busy, bindToken, keepPlan, rememberSelect, isWholeToken,
} from './api.js';
import { exifLens, focalPixelsOf } from './exif.js';

const $ = (id) => document.getElementById(id);

const token = bindToken({
  name: 'scanner', input: $('token'), status: $('token-status'), forget: $('token-forget'), toggle: $('token-toggle'),
});

const SVG = 'http://www.w3.org/2000/svg';
let photoUrl = null;
let photoUnshowable = false;  // the browser cannot draw this file (a TIFF, say); the server can read it
let scanCount = 0;
/** Settles once the plan list has come and the kept plan is chosen (at the end of this file). */
let plansLoaded = Promise.resolve();

function detectPath(extra = {}) {
  return `/api/v1/detect${query({ plan: $('plan').value, tag_size_mm: $('label-size').value, ...extra })}`;
}

function form(file) {
  const data = new FormData();
  data.append('image', file, file.name || 'photo');
  return data;
}

function showPhoto(url, caption, alt) {
  $('scan-photo').src = url;
  $('scan-photo').alt = alt;
  $('photo-caption').textContent = caption;
  $('photo-figure').hidden = photoUnshowable;
}

function svg(name, attributes, text) {
  const node = document.createElementNS(SVG, name);
  for (const [key, value] of Object.entries(attributes)) node.setAttribute(key, value);
  if (text !== undefined) node.textContent = text;
  return node;
}

// A point of the upright photo (the answer's frame, W × H) in the file's stored pixels, for a
// photo whose EXIF orientation `o` the browser did not apply.
function uprightToStored(o, W, H, [x, y]) {
  switch (o) {
    case 2: return [W - x, y];
    case 3: return [W - x, H - y];
    case 4: return [x, H - y];
    case 5: return [y, x];
    case 6: return [y, W - x];
    case 7: return [H - y, W - x];
    case 8: return [H - y, x];
    default: return [x, y];
  }
}

// Mean luma of the picture just inside each tag's black square (its border, a twentieth of the
// side in from each edge and corner), with the corners placed by `place` on a grid of
// viewWidth × viewHeight stretched over the picture. Drawn at most 800 px on its longer side.
function borderLuma(picture, tags, { viewWidth, viewHeight, place }) {
  const scale = Math.min(1, 800 / Math.max(picture.naturalWidth, picture.naturalHeight));
  const canvas = document.createElement('canvas');
  canvas.width = Math.max(1, Math.round(picture.naturalWidth * scale));
  canvas.height = Math.max(1, Math.round(picture.naturalHeight * scale));
  const context = canvas.getContext('2d', { willReadFrequently: true });
  context.drawImage(picture, 0, 0, canvas.width, canvas.height);
  let sum = 0;
  let count = 0;
  for (const tag of tags) {
    const corners = tag.corners_px.map(place);
    const centre = corners.reduce(([sx, sy], [x, y]) => [sx + x / 4, sy + y / 4], [0, 0]);
    const points = [];
    corners.forEach((corner, i) => {
      const next = corners[(i + 1) % 4];
      points.push(corner, [(corner[0] + next[0]) / 2, (corner[1] + next[1]) / 2]);
    });
    for (const [x, y] of points) {
      // A tenth of the way to the centre: a twentieth of the side in, on the black border.
      const px = (x + (centre[0] - x) * 0.1) * canvas.width / viewWidth;
      const py = (y + (centre[1] - y) * 0.1) * canvas.height / viewHeight;
      if (px < 0 || py < 0 || px >= canvas.width || py >= canvas.height) continue;
      const [r, g, b] = context.getImageData(Math.floor(px), Math.floor(py), 1, 1).data;
      sum += 0.2126 * r + 0.7152 * g + 0.0722 * b;
      ++count;
    }
  }
  return count ? sum / count : 255;
}

// The answer's corners are in the photo's pixels after its EXIF orientation (the upright grid).
// Browsers apply the orientation of a JPEG but not always of other files (Chromium shows a WebP
// as stored), so the page finds which grid the picture shows: by its size when the orientation
// turns a photo that is not square a quarter, else by the tags themselves, whose black borders
// are dark only where the picture really has them.
function shownGrid(answer, picture) {
  const { width, height } = answer.image;
  const o = answer.image.exif_orientation || 1;
  const upright = { viewWidth: width, viewHeight: height, place: (point) => point };
  // Not drawn (a TIFF the browser cannot show): no picture for the outline to sit on.
  if (o === 1 || picture.naturalWidth === 0) return upright;
  const stored = {
    viewWidth: o >= 5 ? height : width,
    viewHeight: o >= 5 ? width : height,
    place: (point) => uprightToStored(o, width, height, point),
  };
  const fits = ({ viewWidth, viewHeight }) =>
    picture.naturalWidth === viewWidth && picture.naturalHeight === viewHeight;
  if (fits(upright) !== fits(stored)) return fits(stored) ? stored : upright;
  if (answer.tags.length === 0) return upright;
  return borderLuma(picture, answer.tags, stored) < borderLuma(picture, answer.tags, upright) ? stored : upright;
}

// The SVG's view box is the grid the picture shows, stretched over it.
async function drawOutlines(answer) {
  const outlines = $('outlines');
  outlines.replaceChildren();
  const picture = $('scan-photo');
  await picture.decode().catch(() => {});  // its natural size is known once it is decoded
  const { viewWidth, viewHeight, place } = shownGrid(answer, picture);
  outlines.setAttribute('viewBox', `0 0 ${viewWidth} ${viewHeight}`);
  outlines.setAttribute('preserveAspectRatio', 'none');
  const photoFont = Math.max(viewWidth, viewHeight) / 28;
  const placed = answer.tags.map((tag) => tag.corners_px.map(place));
  const centres = placed.map((corners) => corners.reduce(([sx, sy], [x, y]) => [sx + x / 4, sy + y / 4], [0, 0]));
  answer.tags.forEach((tag, i) => {
    const corners = placed[i];
    const group = svg('g', { class: tag.status, 'data-pincode': tag.pincode || '' });
    group.append(svg('polygon', { points: corners.map(([x, y]) => `${x},${y}`).join(' ') }));
    const centreX = centres[i][0];
    const top = Math.min(...corners.map(([, y]) => y));
    // Sized by the photo, unless another tag is near: then six digits fit in the distance to it
    // (a photo of many tags had its captions piled over each other and over the tags).
    const nearest = Math.min(...centres.map(([x, y], j) => (j === i ? Infinity : Math.hypot(x - centreX, y - centres[i][1]))));
    const fontSize = Math.min(photoFont, nearest / 4);
    group.append(svg('text', { x: centreX, y: Math.max(fontSize, top - fontSize / 3), 'font-size': fontSize, 'text-anchor': 'middle' },
      tag.status === 'unknown_key' ? `key ${tag.key}` : tag.pincode));
    outlines.append(group);
  });
}

function tagCard(tag, approximate) {
  const known = tag.status !== 'unknown_key';
  const distance = tag.pose && Number.isFinite(tag.pose.distance_m)
    ? `${tag.pose.distance_m.toFixed(2)} m${approximate ? ' (approx.)' : ''}` : '—';
  const rows = known
    ? [['Office', tag.office || '—'], ['District', tag.district || '—'], ['State', tag.state || '—'],
      ['Distance', distance], ['Key', tag.key]]
    : [['Key', tag.key], ['Distance', distance],
      ['Note', 'This key belongs to no pincode in the registry. Sort the parcel by hand.']];
  if (tag.status === 'retired') {
    rows.push(['Note', 'This pincode is retired: no new labels are made for it. Check the address on the parcel before it goes to the bin.']);
  }
  // The format cannot tell a mirrored tag from another key's (docs/FORMAT.md, "Mirror images").
  if (tag.mirror_pincode) {
    rows.push(['Mirror', el('span', { class: 'mirror-note' },
      `In a mirrored photo (a front camera's mirror setting) this tag reads as ${tag.mirror_pincode}. ` +
      'Check the pincode printed on the label.')]);
  }
  return el('li', { class: `tag-card ${tag.status}`, 'data-pincode': tag.pincode || '',
    'data-mirror-pincode': tag.mirror_pincode || '' },
    // The bin is what the person holding the parcel acts on: as large as the pincode, beside it.
    el('header', {},
      el('div', { class: 'tag-card-id' },
        el('span', { class: 'big-pin' }, known ? tag.pincode : 'Unknown'),
        badge(tag.status)),
      el('div', { class: 'bin-block' },
        el('span', { class: 'bin-label' }, 'Bin'),
        el('span', { class: 'bin big-bin' }, known ? (tag.bin ?? '—') : 'by hand'))),
    el('dl', { class: 'kv' }, rows.map(([name, value]) => [el('dt', {}, name), el('dd', {}, value)])));
}

// A photo over the server's limits (a phone's 50 MP mode is over the default 40 MP; a large PNG
// may be over the body limit) is drawn again here, upright and smaller, as a JPEG, to fit the
// limits the server's 413 answers give, and that is read instead: a smaller photo rather than
// none. Each 413 may give one limit (the body's is checked first, from the upload's length), so
// the limits learnt are kept and a second refusal draws the photo again under both.
const kShrinkQuality = 0.92;
// Room for the multipart form around the photo, which counts toward the body limit.
const kFormOverheadBytes = 4096;
// A canvas larger than this fails on some browsers (iOS Safari's limit); tried when larger fails.
const kSafeCanvasPixels = 16_777_216;
const kShrinkRounds = 2;

// The limits a refusal gives, added to those already learnt; null when it gives none.
function limitsFrom(error, known = {}) {
  if (!error || error.status !== 413) return null;
  const { max_pixels: maxPixels, max_body_bytes: maxBodyBytes } = error.numbers || {};
  if (!(maxPixels > 0) && !(maxBodyBytes > kFormOverheadBytes)) return null;
  return {
    maxPixels: maxPixels > 0 ? maxPixels : known.maxPixels,
    maxBytes: maxBodyBytes > kFormOverheadBytes ? maxBodyBytes - kFormOverheadBytes : known.maxBytes,
  };
}

// The photo as a JPEG under `limits` ({maxPixels, maxBytes}, either unknown), drawn upright by
// its EXIF orientation on white (a transparent PNG would turn black); null when the browser
// cannot draw the file (a TIFF) or the canvas fails.
async function shrunkToFit(file, limits) {
  let bitmap;
  try {
    bitmap = await createImageBitmap(file, { imageOrientation: 'from-image' });
  } catch {
    return null;
  }
  const canvas = document.createElement('canvas');
  try {
    const { width, height } = bitmap;
    // Just under the limit: a side rounded up must not carry it over.
    let scale = limits.maxPixels ? Math.min(1, Math.sqrt((limits.maxPixels * 0.995) / (width * height))) : 1;
    let canvasFailed = false;
    // A JPEG's size falls about as its pixels do; a few tries find one under the body limit.
    for (let attempt = 0; attempt < 6; ++attempt) {
      if (canvasFailed) scale = Math.min(scale, Math.sqrt(kSafeCanvasPixels / (width * height)));
      canvas.width = Math.max(1, Math.floor(width * scale));
      canvas.height = Math.max(1, Math.floor(height * scale));
      const context = canvas.getContext('2d');
      let blob = null;
      if (context) {
        context.fillStyle = '#fff';
        context.fillRect(0, 0, canvas.width, canvas.height);
        context.imageSmoothingQuality = 'high';
        context.drawImage(bitmap, 0, 0, canvas.width, canvas.height);
        blob = await new Promise((done) => canvas.toBlob(done, 'image/jpeg', kShrinkQuality));
      }
      if (!blob) {
        if (canvasFailed || width * height * scale * scale <= kSafeCanvasPixels) return null;
        canvasFailed = true;
        continue;
      }
      if (!limits.maxBytes || blob.size <= limits.maxBytes) {
        return {
          blob, width: canvas.width, height: canvas.height, fromWidth: width, fromHeight: height,
          pixelLimited: Boolean(limits.maxPixels) && canvas.width * canvas.height < width * height,
        };
      }
      scale *= Math.sqrt((limits.maxBytes * 0.9) / blob.size);
    }
    return null;
  } catch {
    return null;
  } finally {
    bitmap.close();
    // Its pixels are let go now, not when the collector comes.
    canvas.width = 0;
    canvas.height = 0;
  }
}

// Whether the file starts as the photos the server reads do (detector/src/image_io.cpp, the
// same signatures): JPEG, PNG, TIFF or BigTIFF, WebP.
async function startsAsAPhoto(file) {
  const b = new Uint8Array(await file.slice(0, 12).arrayBuffer());
  const at = (offset, ...bytes) => bytes.every((v, i) => b[offset + i] === v);
  const text = (offset, s) => at(offset, ...[...s].map((c) => c.charCodeAt(0)));
  return at(0, 0xff, 0xd8, 0xff) || at(0, 0x89, 0x50, 0x4e, 0x47)
    || text(0, 'II*\0') || text(0, 'MM\0*') || text(0, 'II+\0') || text(0, 'MM\0+')
    || (text(0, 'RIFF') && text(8, 'WEBP'));
}

// A file over the body limit that the browser cannot draw smaller: when it is no photo at all,
// that is what to say (the server refuses by size before it looks, so its 413 named only the
// size, in bytes); null when it starts as a photo.
async function notAPhotoOver(file, refusal) {
  if (await startsAsAPhoto(file).catch(() => true)) return null;
  const limit = refusal.numbers && refusal.numbers.max_body_bytes;
  const mb = (bytes) => `${(bytes / 1_048_576).toFixed(bytes < 10_485_760 ? 1 : 0)} MB`;
  return { title: 'Not a photo',
    message: `“${file.name}” is not a JPEG, PNG, TIFF or WebP photo${limit ? `, and at ${mb(file.size)} it is over the server's ${mb(limit)} limit too` : ''}. Choose a photo of the label.` };
}

function megapixels(pixels) {
  return `${(pixels / 1e6).toFixed(pixels < 1e7 ? 1 : 0)} MP`;
}

// Nothing of the last answer stays on screen: its message, cards, outlines and photo.
function clearResults() {
  show($('scan-msg'));
  show($('tags'));
  $('outlines').replaceChildren();
  $('scan-photo').removeAttribute('data-outlined');
  $('photo-figure').hidden = true;
}

async function scan() {
  const file = $('photo').files[0];
  if (!file) return;
  const run = ++scanCount;
  // Nothing of the last scan stays on screen once another photo is chosen.
  clearResults();
  $('summary').textContent = '';
  if (!token()) {
    show($('scan-msg'), el('div', { class: 'alert alert-error', role: 'alert' },
      el('strong', { class: 'problem-title' }, 'No scanner token'),
      el('p', { class: 'problem-detail' }, 'Paste a scanner token above: the photo is read as soon as it is there.')));
    waitingForToken = true;
    $('token').focus();
    return;
  }
  waitingForToken = false;
  await plansLoaded;
  if (run !== scanCount) return;
  if (photoUrl) URL.revokeObjectURL(photoUrl);
  photoUrl = URL.createObjectURL(file);
  photoUnshowable = false;
  showPhoto(photoUrl, 'Your photo. Reading…', 'The photo being read');
  $('summary').textContent = 'Reading the photo…';
  let answer;
  let shrunk = null;
  let fileLens;  // the photo's EXIF lens, read at the first shrink and kept for the rounds after
  try {
    let limits = {};
    for (let round = 0; ; ++round) {
      try {
        const photo = shrunk ? new File([shrunk.blob], 'photo-smaller.jpg', { type: 'image/jpeg' }) : file;
        // The smaller photo lost the file's EXIF: its lens goes as the camera's focal length.
        const lens = shrunk && shrunk.focalPx ? { fx: shrunk.focalPx.toFixed(3), fy: shrunk.focalPx.toFixed(3) } : {};
        answer = await api(detectPath(lens), { method: 'POST', token: token(), body: form(photo) });
        break;
      } catch (error) {
        if (run !== scanCount) return;
        limits = round < kShrinkRounds ? limitsFrom(error, limits) : null;
        if (!limits) throw error;
        shrunk = await shrunkToFit(file, limits);
        if (!shrunk) throw await notAPhotoOver(file, error) || error;
        if (fileLens === undefined) fileLens = await exifLens(file);
        shrunk.focalPx = focalPixelsOf(fileLens, shrunk.fromWidth, shrunk.fromHeight, shrunk.width, shrunk.height);
        if (run !== scanCount) return;
        // What is read is what is shown: the outlines are in the smaller photo's pixels.
        URL.revokeObjectURL(photoUrl);
        photoUrl = URL.createObjectURL(shrunk.blob);
        photoUnshowable = false;
        showPhoto(photoUrl, 'Your photo, made smaller. Reading…', 'The photo being read, made smaller');
        $('summary').textContent = `The photo is over the server's limit: reading it at ${shrunk.width} × ${shrunk.height}…`;
      }
    }
  } catch (error) {
    if (run !== scanCount) return;
    $('summary').textContent = failureSummary(error);
    $('photo-caption').textContent = 'Your photo.';
    show($('scan-msg'), problemBox(error));
    reveal($('scan-msg'));
    return;
  }
  if (run !== scanCount) return;
  const approximate = answer.intrinsics && answer.intrinsics.source === 'assumed';
  const n = answer.tag_count;
  // The bins are the plan's the server used (its name isolated: it may be written right to left).
  show($('summary'), `${n === 0 ? 'No tag' : n === 1 ? '1 tag' : `${n} tags`} read in `
    + `${Math.round(answer.time_ms.total)} ms · photo ${answer.image.width} × ${answer.image.height} · plan `,
    el('bdi', { class: 'plan-used' }, answer.plan || $('plan').value || 'default'),
    approximate ? ' · distances approximate (camera field of view assumed)' : null,
    photoUnshowable ? kUnshowable : null);
  if (shrunk) {
    // Smaller tags are harder to read. What to change depends on the limit: the camera's
    // resolution, or the file it saves.
    $('summary').append(el('span', { class: 'shrunk-note' },
      ` · made smaller to fit the server's limit (${shrunk.fromWidth} × ${shrunk.fromHeight}, `
      + `${megapixels(shrunk.fromWidth * shrunk.fromHeight)}): `
      + (shrunk.pixelLimited || file.type === 'image/jpeg' ? 'set the camera to a lower resolution' : 'send the photo as a JPEG')));
  }
  show($('tags'), answer.tags.map((tag) => tagCard(tag, approximate)));
  if (n === 0) {
    // The server says when the photo itself could hold no tag (no colour): that, not the
    // general advice, is what the person holding the camera must change.
    const warnings = (answer.warnings || []).map((w) => w.message);
    show($('tags'), el('li', { class: 'alert alert-info' },
      warnings.length ? `No PinTag found: ${warnings.join('; ')}.`
        : 'No PinTag found. Hold the camera steady, fill more of the frame with the label and avoid glare.'));
  }
  await drawOutlines(answer);
  if (run !== scanCount) return;
  showPhoto(photoUrl, n ? `Your photo with ${n === 1 ? 'the tag' : 'the tags'} outlined.` : 'Your photo.',
    `The photo with ${n} ${n === 1 ? 'tag' : 'tags'} outlined${n ? `: ${answer.tags.map((t) => t.pincode || 'unknown key').join(', ')}` : ''}`);
  $('scan-photo').dataset.outlined = '1';
  reveal($('summary'));
}

// What the summary says when no answer came: what failed, not only that the photo was not read
// (a token refused is not a photo that could not be read).
function failureSummary(error) {
  const status = error && error.status;
  if (status === 401 || (status === 0 && error.title === 'Token not valid')) {
    return 'Not read: the scanner token was not accepted.';
  }
  if (status === 403) return 'Not read: this token may not read photos (it needs the scanner or admin role).';
  if (status === 0) return 'Not read: the server did not answer.';
  if (status === 429 || status === 503) return 'Not read: the server is busy. Try the photo again shortly.';
  if (status >= 500) return 'Not read: the server failed on this photo.';
  return 'The photo could not be read.';
}

const kUnshowable = ' · this browser cannot show the photo itself (e.g. a TIFF)';

// On a phone the answer lands below the screen: scroll to it unless it is already in view.
function reveal(node) {
  const box = node.getBoundingClientRect();
  if (box.top < 0 || box.bottom > window.innerHeight) node.scrollIntoView({ block: 'start' });
}

// A file the browser cannot show (not an image): no broken picture, the problem box says why.
$('scan-photo').addEventListener('error', () => {
  photoUnshowable = true;
  $('photo-figure').hidden = true;
  if ($('scan-photo').dataset.outlined && !$('summary').textContent.includes('cannot show the photo')) {
    $('summary').append(kUnshowable);
  }
});

// A photo refused for want of a token is read once a whole token is pasted: choosing the same
// file again fires no change, and "Read tags" is below the fold on a phone.
let waitingForToken = false;
$('token').addEventListener('input', () => {
  if (waitingForToken && $('photo').files.length && isWholeToken(token())) {
    busy($('scan'), scan);
  }
});

$('photo').addEventListener('change', () => {
  $('scan').disabled = !$('photo').files.length;
  // Which photo is being read, in the box that chose it (the input itself is hidden).
  $('photo-name').textContent = $('photo').files.length ? `Chosen: ${$('photo').files[0].name}` : 'No photo chosen';
  $('scan-photo').removeAttribute('data-outlined');
  $('outlines').replaceChildren();
  busy($('scan'), scan);
});
$('scan-form').addEventListener('submit', (event) => {
  event.preventDefault();
  busy($('scan'), scan);
});
// The bins follow the sort plan and the distances the label size: a change of either reads the
// photo again, as the counter draws its preview again. Without a token the old answer goes, so
// no bin of another plan stays on screen as if it were this one's.
function settingsChanged() {
  if (!$('photo').files.length) return;
  if (token()) {
    busy($('scan'), scan);
    return;
  }
  ++scanCount;  // an answer still on its way was asked with the old settings
  clearResults();
  $('summary').textContent = 'The sort plan or label size changed: paste a scanner token above to read the photo again.';
}
// A hub's scanner keeps its plan and label size from one visit to the next (they reset to the
// default plan on every reload, and the bins shown were another plan's).
rememberSelect($('label-size'), 'scanner.size');
$('plan').addEventListener('change', settingsChanged);
$('label-size').addEventListener('change', settingsChanged);

// A read waits for the kept plan (plansLoaded): a photo chosen before the list came would be read
// with the server's default plan.
plansLoaded = keepPlan($('plan'), 'scanner.plan');
