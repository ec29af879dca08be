// The lens a photo was taken with, from its EXIF block. A photo the scanner page makes smaller is
// redrawn on a canvas, which drops the file's metadata; without its focal length the server
// would assume a field of view and give approximate distances. So the page reads the lens here
// and sends it as `fx`/`fy` for the smaller photo, by the server's own rule (docs/API.md,
// /detect: the 35 mm-equivalent focal length, else the focal length over the focal plane's
// resolution, a 35 mm-equivalent outside 2–2000 mm taken as unknown).

const kFullFrameDiagonalMm = Math.hypot(36, 24);
const kMinEquivalentMm = 2;
const kMaxEquivalentMm = 2000;
const kExifHeader = [0x45, 0x78, 0x69, 0x66, 0, 0];  // "Exif\0\0"

function startsWith(bytes, at, prefix) {
  return at + prefix.length <= bytes.length && prefix.every((b, i) => bytes[at + i] === b);
}

function ascii(bytes, at, length) {
  return String.fromCharCode(...bytes.subarray(at, at + length));
}

// The TIFF-structured EXIF block of a JPEG (APP1 "Exif\0\0" before the first scan), a WebP
// (its EXIF chunk) or a PNG (its eXIf chunk); null when the file has none.
function exifBlock(bytes) {
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes[0] === 0xff && bytes[1] === 0xd8) {
    // The segments before the first scan, as the server walks them: 0xFF fill bytes skipped, and
    // a segment that runs past the file's end is the end (its EXIF, cut short, is not read).
    for (let at = 2; at + 4 <= bytes.length && bytes[at] === 0xff;) {
      const marker = bytes[at + 1];
      if (marker === 0xff) { at += 1; continue; }
      if (marker === 0xda || marker === 0xd9) return null;  // the scan starts: no EXIF before it
      const length = view.getUint16(at + 2);
      if (length < 2 || at + 2 + length > bytes.length) return null;
      if (marker === 0xe1 && length >= 2 + kExifHeader.length && startsWith(bytes, at + 4, kExifHeader)) {
        return bytes.subarray(at + 4 + kExifHeader.length, at + 2 + length);
      }
      at += 2 + length;
    }
    return null;
  }
  if (ascii(bytes, 0, 4) === 'RIFF' && ascii(bytes, 8, 4) === 'WEBP') {
    for (let at = 12; at + 8 <= bytes.length;) {
      const size = view.getUint32(at + 4, true);
      if (ascii(bytes, at, 4) === 'EXIF') {
        const chunk = bytes.subarray(at + 8, Math.min(bytes.length, at + 8 + size));
        // Some writers keep the JPEG's "Exif\0\0" in front of the TIFF header.
        return startsWith(chunk, 0, kExifHeader) ? chunk.subarray(kExifHeader.length) : chunk;
      }
      at += 8 + size + (size % 2);
    }
    return null;
  }
  if (startsWith(bytes, 0, [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a])) {
    for (let at = 8; at + 8 <= bytes.length;) {
      const size = view.getUint32(at);
      if (ascii(bytes, at + 4, 4) === 'eXIf') return bytes.subarray(at + 8, Math.min(bytes.length, at + 8 + size));
      at += 12 + size;
    }
  }
  return null;
}

// The lens fields of a TIFF-structured EXIF block (IFD0, then its EXIF IFD), each a positive
// number or undefined. Any offset outside the block ends the reading: a broken block gives what
// was read before it.
function lensFields(tiff) {
  const fields = {};
  if (tiff.length < 8) return fields;
  const view = new DataView(tiff.buffer, tiff.byteOffset, tiff.byteLength);
  const little = tiff[0] === 0x49 && tiff[1] === 0x49;
  if (!little && !(tiff[0] === 0x4d && tiff[1] === 0x4d)) return fields;
  if (view.getUint16(2, little) !== 42) return fields;
  const u16 = (at) => view.getUint16(at, little);
  const u32 = (at) => view.getUint32(at, little);
  // An entry's number: SHORT or LONG held in the entry, RATIONAL at the offset it gives.
  const value = (entry) => {
    const type = u16(entry + 2);
    if (type === 3) return u16(entry + 8);
    if (type === 4) return u32(entry + 8);
    if (type === 5) {
      const at = u32(entry + 8);
      if (at + 8 > tiff.length) return undefined;
      const denominator = u32(at + 4);
      return denominator ? u32(at) / denominator : undefined;
    }
    return undefined;
  };
  const entries = (ifd) => {
    if (ifd + 2 > tiff.length) return [];
    const count = u16(ifd);
    const list = [];
    for (let i = 0; i < count && ifd + 2 + 12 * (i + 1) <= tiff.length; ++i) list.push(ifd + 2 + 12 * i);
    return list;
  };
  const names = { 0xa405: 'equivalentMm', 0x920a: 'focalMm', 0xa20e: 'planeXResolution', 0xa210: 'planeUnit' };
  const take = (list) => {
    for (const entry of list) {
      const name = names[u16(entry)];
      const number = name ? value(entry) : undefined;
      // A 0 ("unknown") is no value, as the server's reader has it.
      if (number > 0 && Number.isFinite(number)) fields[name] = number;
    }
  };
  // The lens belongs in the EXIF directory. The server's EXIF reader (OpenImageIO's) also takes
  // it from IFD0, and IFD0's word wins there: so here, the EXIF directory first, then IFD0.
  const ifd0 = entries(u32(4));
  const exifIfd = ifd0.find((entry) => u16(entry) === 0x8769);
  if (exifIfd !== undefined) take(entries(u32(exifIfd + 8)));
  take(ifd0);
  return fields;
}

function pixelsPerMm(resolution, unit) {
  if (unit === 2) return resolution / 25.4;
  if (unit === 3) return resolution / 10;
  if (unit === 4) return resolution;
  return undefined;
}

/**
 * The lens fields of `file`'s EXIF (none: {}), read once per photo however often it is drawn
 * smaller; null when the file cannot be read again or its EXIF block is cut short.
 */
export async function exifLens(file) {
  try {
    const block = exifBlock(new Uint8Array(await file.arrayBuffer()));
    return block ? lensFields(block) : {};
  } catch {
    return null;
  }
}

/**
 * The focal length in pixels of a photo whose EXIF lens is `lens` (exifLens) drawn at `width` ×
 * `height`, when the lens is one the server would take; `fromWidth` × `fromHeight` is the photo's
 * own size (either way up: only its diagonal counts). null when there is no lens, or none that is
 * plausible.
 */
export function focalPixelsOf(lens, fromWidth, fromHeight, width, height) {
  if (!lens) return null;
  const fromDiagonal = Math.hypot(fromWidth, fromHeight);
  let equivalentMm = lens.equivalentMm > 0 ? lens.equivalentMm : undefined;
  if (!equivalentMm && lens.focalMm > 0 && lens.planeXResolution > 0) {
    // As the server: a unit missing or 0 is inches.
    const perMm = pixelsPerMm(lens.planeXResolution, lens.planeUnit > 0 ? lens.planeUnit : 2);
    if (perMm) equivalentMm = (lens.focalMm * perMm * kFullFrameDiagonalMm) / fromDiagonal;
  }
  if (!(equivalentMm >= kMinEquivalentMm && equivalentMm <= kMaxEquivalentMm)) return null;
  return (equivalentMm * Math.hypot(width, height)) / kFullFrameDiagonalMm;
}
