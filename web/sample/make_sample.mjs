// Writes a synthetic, filled report page for development and as a browser-test fixture:
//   node web/sample/make_sample.mjs OUT.html [--template T.html] [--big] [--no-design]
//        [--no-timeline] [--no-events] [--no-contour]
// A 60 x 40 x 10 mm plate with a circular pocket, finished by a raster along x
// (finish.ngc, one NC line per 0.5 mm row, lines 100..180). It carries a gouge (dent)
// 0.3 mm deep at (40, 25) cut by finish.ngc:150, an excess bump 0.25 mm high at (15, 12)
// cut by finish.ngc:124, a shallow gouge 0.05 mm at (30, 8) cut by finish.ngc:116, three
// events and a timeline. --big refines the grid to ~2 million triangles (stress test).
// The template is filled exactly as the vcut CLI does it: the one marker is replaced by the
// JSON text with "</" written as "<\/" and "<!--" as "<\u0021--".

import { readFile, writeFile, rename, mkdtemp, rm } from 'node:fs/promises';
import { spawnSync } from 'node:child_process';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const MARKER = '__VCUT_REPORT_DATA__';
const here = path.dirname(fileURLToPath(import.meta.url));

const args = process.argv.slice(2);
const flags = new Set(args.filter((a) => a.startsWith('--') && a !== '--template'));
const tIdx = args.indexOf('--template');
const templateArg = tIdx >= 0 ? args[tIdx + 1] : null;
const out = args.find((a, i) => !a.startsWith('--') && (tIdx < 0 || i !== tIdx + 1));
if (!out) {
  console.error('usage: node web/sample/make_sample.mjs OUT.html [--template T.html] [--big] [--no-design] [--no-timeline] [--no-events] [--no-contour]');
  process.exit(2);
}
const BIG = flags.has('--big');
const WITH_DESIGN = !flags.has('--no-design');

// ---- geometry ---------------------------------------------------------------------------

const LX = 60, LY = 40, H = 10;
const STEP = BIG ? 0.045 : 0.25;
const NX = Math.round(LX / STEP), NY = Math.round(LY / STEP);
const POCKET = { x: 30, y: 20, r: 13, depth: 3, band: 4 };

// A shallow round pocket with a smooth (cosine) flank, so the grid samples it cleanly.
function designZ(x, y) {
  const d = Math.hypot(x - POCKET.x, y - POCKET.y);
  if (d >= POCKET.r) return 0;
  const u = Math.min(1, (POCKET.r - d) / POCKET.band);
  return (-POCKET.depth * (1 - Math.cos(Math.PI * u))) / 2;
}

const bump = (x, y, cx, cy, r, h) => h * Math.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (r * r));
function machinedOffset(x, y) {
  let dz = 0;
  dz -= bump(x, y, 40, 25, 1.6, 0.3); // the gouge
  dz += bump(x, y, 15, 12, 2.2, 0.25); // the excess
  dz -= bump(x, y, 30, 8, 1.0, 0.05); // a shallow gouge, just beyond 0.02
  dz += 0.006 * Math.sin((y / 0.5) * Math.PI * 2) ** 2; // scallops of the raster, within tolerance
  return dz;
}

// Finish raster: one row per 0.5 mm of y, NC line 100 + row.
const rowLine = (y) => 100 + Math.max(0, Math.min(80, Math.round(y / 0.5)));

const pos = [];
const design = [];
const dev = [];
const src = [];
const tri = [];
const sources = [];
const sourceIndex = new Map();
function sourceOf(file, line, text) {
  const k = `${file}:${line}`;
  if (!sourceIndex.has(k)) {
    sourceIndex.set(k, sources.length);
    sources.push({ file, line, text });
  }
  return sourceIndex.get(k);
}
const finishText = (line) => {
  const row = line - 100;
  const y = (row * 0.5).toFixed(1);
  return row % 2 === 0 ? `G1 X${LX + 3} Y${y} F1200` : `G1 X-3 Y${y} F1200`;
};
for (let l = 100; l <= 180; l++) sourceOf('finish.ngc', l, finishText(l));
sourceOf('rough.ngc', 42, 'G1 Z-10.5 F600 (side walls)');
sourceOf('finish.ngc', 90, '(MSG, fixture: </script> <!-- <script> & "quotes")');

function vertex(x, y, zMachined, zDesign, s) {
  pos.push(x, y, zMachined);
  design.push(x, y, zDesign);
  dev.push(WITH_DESIGN ? zMachined - zDesign : NaN);
  src.push(s);
  return pos.length / 3 - 1;
}

// Top height field.
const top = new Array((NX + 1) * (NY + 1));
for (let j = 0; j <= NY; j++) {
  for (let i = 0; i <= NX; i++) {
    const x = i * STEP, y = j * STEP;
    const zd = designZ(x, y);
    top[j * (NX + 1) + i] = vertex(x, y, zd + machinedOffset(x, y), zd, sourceIndex.get(`finish.ngc:${rowLine(y)}`));
  }
}
for (let j = 0; j < NY; j++) {
  for (let i = 0; i < NX; i++) {
    const a = top[j * (NX + 1) + i], b = a + 1, c = top[(j + 1) * (NX + 1) + i], d = c + 1;
    tri.push(a, b, d, a, d, c);
  }
}
// Side walls (cut by rough.ngc:42) and bottom (initial stock, never cut), own vertices for
// sharp edges. Outward winding.
const wallSrc = sourceIndex.get('rough.ngc:42');
function wall(points, outward) {
  // points: [x, y] along the top edge; a strip from z=top down to z=-H
  const upper = [], lower = [];
  for (const [x, y] of points) {
    const z = designZ(x, y) + machinedOffset(x, y);
    upper.push(vertex(x, y, z, designZ(x, y), wallSrc));
    lower.push(vertex(x, y, -H, -H, wallSrc));
  }
  for (let k = 0; k + 1 < points.length; k++) {
    const a = upper[k], b = upper[k + 1], c = lower[k], d = lower[k + 1];
    if (outward) tri.push(a, c, d, a, d, b); else tri.push(a, b, d, a, d, c);
  }
}
const along = (n, f) => Array.from({ length: n + 1 }, (_, k) => f(k));
wall(along(NX, (k) => [k * STEP, 0]), true);
wall(along(NX, (k) => [k * STEP, LY]), false);
wall(along(NY, (k) => [0, k * STEP]), false);
wall(along(NY, (k) => [LX, k * STEP]), true);
{
  const b = [[0, 0], [LX, 0], [LX, LY], [0, LY]].map(([x, y]) => vertex(x, y, -H, -H, -1));
  tri.push(b[0], b[2], b[1], b[0], b[3], b[2]);
}

const nV = pos.length / 3;
const nT = tri.length / 3;
const b64 = (typed) => Buffer.from(typed.buffer, typed.byteOffset, typed.byteLength).toString('base64');
const meshDoc = {
  vertices: nV,
  triangles: nT,
  positions: b64(new Float32Array(pos)),
  indices: b64(new Uint32Array(tri)),
  deviation: WITH_DESIGN ? b64(new Float32Array(dev)) : null,
  source: b64(new Int32Array(src)),
};

// ---- regions, events, histogram, timeline ----------------------------------------------

function region(kind, cx, cy, r, depth, lines, ncLines) {
  const z = designZ(cx, cy) + machinedOffset(cx, cy);
  return {
    kind, depth_mm: depth, area_mm2: Math.round(Math.PI * r * r * 0.55 * 1000) / 1000,
    centroid: [cx, cy, z], deepest: [cx, cy, z], lines, tools: [2], initial_stock: false,
    nc: ncLines.map((l) => ({ file: 'finish.ngc', line: l, text: finishText(l) })),
  };
}
const gTol = 0.02, eTol = 0.1;
const regions = !WITH_DESIGN ? [] : [
  region('gouge', 40, 25, 1.6, 0.2976, ['finish.ngc:148-152'], [148, 149, 150, 151, 152]),
  region('gouge', 30, 8, 0.7, 0.0498, ['finish.ngc:116'], [116]),
  region('excess', 15, 12, 2.2, 0.2487, ['finish.ngc:122-126', 'finish.ngc:90'], [122, 123, 124, 125, 126]),
];
const events = flags.has('--no-events') ? [] : [
  { kind: 'rapid_into_stock', line: 'rough.ngc:12', detail: 'G0 move cuts 0.5 mm into the stock', depth_mm: 0.5, where: [5, 5, 1.5],
    nc: [{ file: 'rough.ngc', line: 12, text: 'G0 X5 Y5 Z1.5' }] },
  { kind: 'holder_collision', line: 'finish.ngc:171', detail: 'holder HSK63 touches the stock (0.12 mm)', depth_mm: 0.12, where: [52, 35, 0.2],
    nc: [{ file: 'finish.ngc', line: 171, text: finishText(171) }] },
  { kind: 'axis_limited_speed', line: 'finish.ngc:130', detail: 'feed limited to 840 mm/min by the Y axis acceleration', depth_mm: null, where: null,
    nc: [{ file: 'finish.ngc', line: 130, text: finishText(130) }] },
];

let histogram = null;
if (WITH_DESIGN) {
  const edges = [null, -0.3, -0.2, -0.1, -0.06, -0.04, -0.02, -0.01, 0, 0.01, 0.02, 0.05, 0.1, 0.2, null];
  const counts = new Array(edges.length - 1).fill(0);
  for (const d of dev) {
    let k = 0;
    while (k < counts.length - 1 && edges[k + 1] != null && d >= edges[k + 1]) k++;
    counts[k]++;
  }
  histogram = { edges_mm: edges, counts, area_mm2: counts.map((c) => Math.round(c * STEP * STEP * 1000) / 1000) };
}

let timeline = null;
if (!flags.has('--no-timeline')) {
  const t = [], feed = [], err = [];
  let prev = 0;
  for (let k = 0; k <= 8125; k++) {
    const ts = k * 0.1;
    // 81 raster rows of ~9.6 s each: accelerate, cut at 1200 mm/min, decelerate, short rapid.
    const phase = ts % 10;
    let f;
    if (phase < 0.4) f = 5000 * (phase / 0.4);
    else if (phase < 0.6) f = 5000;
    else if (phase < 1.0) f = 5000 - 3800 * ((phase - 0.6) / 0.4);
    else if (phase < 9.4) f = 1200 * (1 + 0.04 * Math.sin(ts * 3.1));
    else f = 1200 * (1 - (phase - 9.4) / 0.6);
    if (ts > 300 && ts < 330) f = Math.min(f, 840);
    t.push(Math.round(ts * 10) / 10);
    feed.push(Math.round(f * 10) / 10);
    err.push(Math.round((Math.abs(f - prev) * 0.012 + 0.8 + 0.5 * Math.sin(ts * 7)) * 100) / 100);
    prev = f;
  }
  timeline = { t_s: t, feed_mm_min: feed, contour_error_um: flags.has('--no-contour') ? null : err };
}

const doc = {
  schema: 'vcut-report-page/1',
  title: BIG ? 'sample plate (2M triangles)' : 'sample plate',
  job: {
    name: 'sample', file: 'web/sample/job.yaml', engine: 'dexel', resolution_mm: STEP, threads: 2, machine: '3axis',
    gouge_tolerance_mm: gTol, excess_tolerance_mm: eTol, collision_tolerance_mm: 0.01,
    settings: [['program', 'rough.ngc, finish.ngc'], ['tools', 'T1 D10 flat, T2 D6 ball'], ['densify step', '0.5 mm'],
      ['stock', 'box 64 × 44 × 14 mm'], ['design', WITH_DESIGN ? 'plate.stl' : '(none)']],
  },
  summary: {
    blocks: 1234, moves: 4567, cutting_moves: 4012, removed_volume_mm3: 24180.5, initial_volume_mm3: 39424,
    max_gouge_mm: WITH_DESIGN ? 0.2976 : null, max_excess_mm: WITH_DESIGN ? 0.2487 : null, wall_time_s: 9.1, peak_memory_mb: 452,
    cycle_time_s: 812.5, stage_seconds: [['read', 0.3], ['poses', 0.8], ['cut', 6.2], ['mesh', 1.1], ['compare', 0.5], ['report', 0.2]],
    triangles_shown: nT, triangles_machined: BIG ? nT : nT * 3,
  },
  mesh: meshDoc,
  design: WITH_DESIGN ? {
    vertices: nV, triangles: nT, positions: b64(new Float32Array(design)), indices: b64(new Uint32Array(tri)),
  } : null,
  stock: { box: { min: [-2, -2, -H - 2], max: [LX + 2, LY + 2, 2] } },
  sources,
  regions,
  events,
  histogram,
  timeline,
};

// ---- fill the template ------------------------------------------------------------------

async function templateText() {
  if (templateArg) return readFile(templateArg, 'utf8');
  const dir = await mkdtemp(path.join(os.tmpdir(), 'vcut-tpl-'));
  try {
    const tpl = path.join(dir, 'template.html');
    const r = spawnSync(process.execPath, [path.join(here, '..', 'build.mjs'), tpl], { stdio: 'inherit' });
    if (r.status !== 0) throw new Error('building the template failed');
    return await readFile(tpl, 'utf8');
  } finally {
    await rm(dir, { recursive: true, force: true });
  }
}

const template = await templateText();
const parts = template.split(MARKER);
if (parts.length !== 2) {
  console.error(`make_sample: the template must contain ${MARKER} exactly once (found ${parts.length - 1})`);
  process.exit(1);
}
const json = JSON.stringify(doc).split('</').join('<\\/').split('<!--').join('<\\u0021--');
const html = parts[0] + json + parts[1];
const tmp = `${out}.tmp`;
await writeFile(tmp, html, 'utf8');
await rename(tmp, out);
console.log(`wrote ${out}: ${nV} vertices, ${nT} triangles, ${(Buffer.byteLength(html) / 1e6).toFixed(1)} MB`);
