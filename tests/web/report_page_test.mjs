// Real-browser test of a filled vcut report page (headless Chromium via playwright-core).
//   node tests/web/report_page_test.mjs REPORT.html "file:line" SCREENSHOT.png
//   node tests/web/report_page_test.mjs REPORT.html "collision=file:line" SCREENSHOT.png
// Checks: no console/page errors and no network request; the page becomes ready; the gouge
// table has a row whose NC lines contain file:line; clicking it flies the camera to the
// region's deepest point (from the page's own data) and shows the line's text in the NC
// panel; the WebGL canvas drew an image (not one flat colour). Where the report has a
// playback: the slider at the middle frame poses the machine and shows the part as cut by
// then (fewer triangles than at the end), and Play advances the frames.
// With collision=file:line, instead of the gouge: the slider driven to the machine collision
// at that line poses its two bodies so that their boxes, as the page places them, overlap by
// the depth vcut measured (FCL, in C++), and not at the first frame; "Next event" from the
// start lands on the first event's frame; clicking a collision found between two poses shows
// the machine at that instant, its two bodies' boxes overlapping; with the machine frame on,
// the bed stands still.
// Exit 0: all checks passed. 1: a check failed (each printed) or the report is missing.
// 2: usage. 77 (skip): no Chromium at $VCUT_CHROMIUM or /usr/bin/chromium (1 when
// VCUT_REQUIRE_PEERS=1, as make test sets it).

import { createRequire } from 'node:module';
import { existsSync } from 'node:fs';
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

const here = path.dirname(fileURLToPath(import.meta.url));
const webDir = path.resolve(here, '..', '..', 'web');
const TARGET_TOLERANCE_MM = 1e-3; // camera target vs region.deepest after the fly-to
const READY_TIMEOUT_MS = 60000;

const [reportArg, lineArg, shotArg] = process.argv.slice(2);
if (!reportArg || !lineArg || !shotArg || process.argv.length > 5) {
  console.error('usage: node tests/web/report_page_test.mjs REPORT.html "file:line" SCREENSHOT.png');
  process.exit(2);
}
const executablePath = process.env.VCUT_CHROMIUM || '/usr/bin/chromium';
if (!existsSync(executablePath)) {
  // make test installs Chromium and sets VCUT_REQUIRE_PEERS: there a missing one fails.
  const required = process.env.VCUT_REQUIRE_PEERS === '1';
  console.log(`${required ? 'FAIL' : 'SKIP'}: no Chromium at ${executablePath} (install chromium, or set VCUT_CHROMIUM)`);
  process.exit(required ? 1 : 77);
}
const collisionMode = lineArg.startsWith('collision=');
const lm = /^(.*):(\d+)$/.exec(collisionMode ? lineArg.slice('collision='.length) : lineArg);
if (!lm) {
  console.error(`bad line argument "${lineArg}": expected file:line`);
  process.exit(2);
}
const wantFile = lm[1];
const wantLine = Number(lm[2]);
const reportPath = path.resolve(reportArg);
if (!existsSync(reportPath)) {
  console.log(`FAIL no such report: ${reportPath}`);
  process.exit(1);
}

// ---- helpers ------------------------------------------------------------------------------

// The report JSON, read from the HTML file itself (the page clears its data element after
// parsing). Cached per run.
let reportDoc = null;
async function reportJson(reportFile) {
  if (reportDoc) return reportDoc;
  const html = await readFile(reportFile, 'utf8');
  const open = '<script id="vcut-data" type="application/json">';
  const a = html.indexOf(open);
  const b = a >= 0 ? html.indexOf('</script>', a + open.length) : -1;
  if (a < 0 || b < 0) throw new Error('report has no vcut-data element');
  reportDoc = JSON.parse(html.slice(a + open.length, b));
  return reportDoc;
}
async function readRegions(file) {
  return (await reportJson(file)).regions || [];
}
async function readSources(file) {
  return (await reportJson(file)).sources || [];
}

function ncText(region, regions, file, line, sources) {
  const hit = (e) => e && sameFile(String(e.file), file) && Number(e.line) === line && typeof e.text === 'string';
  for (const e of region.nc || []) if (hit(e)) return e.text;
  for (const e of sources) if (hit(e)) return e.text;
  for (const r of regions) for (const e of r.nc || []) if (hit(e)) return e.text;
  return null;
}

// Distinct colours and the share of the most common one, decoded in the page with a 2D
// canvas (the PNG goes in as a data: URL, which the network check allows).
async function imageStats(page, png) {
  return page.evaluate(async (b64) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const ctx = c.getContext('2d');
    ctx.drawImage(img, 0, 0);
    const px = ctx.getImageData(0, 0, c.width, c.height).data;
    const counts = new Map();
    for (let i = 0; i < px.length; i += 4) {
      const k = (px[i] << 16) | (px[i + 1] << 8) | px[i + 2];
      counts.set(k, (counts.get(k) || 0) + 1);
    }
    let max = 0;
    for (const v of counts.values()) max = Math.max(max, v);
    return { distinct: counts.size, dominantShare: max / (px.length / 4) };
  }, png.toString('base64'));
}

// ---- playback ---------------------------------------------------------------------------

const int32s = (b64) => {
  const buf = Buffer.from(b64, 'base64');
  return new Int32Array(buf.buffer, buf.byteOffset, buf.length / 4);
};
// How far two boxes overlap along each axis (negative: apart along it).
const overlaps = (a, b) => [0, 1, 2].map((k) => Math.min(a.max[k], b.max[k]) - Math.max(a.min[k], b.min[k]));

async function setSlider(page, frame) {
  await page.locator('#playback-slider').fill(String(frame));
  await page.waitForFunction((f) => window.vcutPlayback.frame() === f, frame, { timeout: 5000, polling: 50 });
}

// Any report with a playback: the middle frame shows the part as cut by then, Play advances.
async function checkPlayback(page) {
  const doc = await reportJson(reportPath);
  if (!doc.playback) {
    check(true, 'no playback in this report');
    return;
  }
  const frames = doc.playback.frames.count;
  const total = await page.evaluate(() => window.vcutPlayback.partTriangles());
  check(total === doc.summary.triangles_shown, `the last frame shows the whole part (${total} triangles)`);
  const middle = Math.floor(frames / 2);
  await setSlider(page, middle);
  const shown = await page.evaluate(() => window.vcutPlayback.partTriangles());
  check(shown < total, `frame ${middle} of ${frames} shows the part as cut by then (${shown} of ${total} triangles)`);
  check(await page.evaluate(() => window.vcutPlayback.machineVisible()), 'the slider shows the machine');
  const names = await page.evaluate(() => window.vcutPlayback.bodyNames());
  check(names.some((n) => / cutter$/.test(n)), `the tool is among the bodies (${names.length} bodies)`);
  // The keys: the right arrow steps a frame (the focus on the page, not on a control).
  await page.evaluate(() => document.activeElement && document.activeElement.blur());
  await page.keyboard.press('ArrowRight');
  check(await page.evaluate(() => window.vcutPlayback.frame()) === middle + 1, 'the right arrow steps one frame');
  await page.keyboard.press('ArrowLeft');
  await page.selectOption('#playback-speed', '500');
  await page.locator('#playback-play').click();
  await page.waitForTimeout(400);
  const after = await page.evaluate(() => window.vcutPlayback.frame());
  await page.locator('#playback-play').click();
  check(after > middle, `Play advances the frames (${middle} -> ${after})`);
  await setSlider(page, frames - 1);
}

// The machine-collision example: the slider driven to the collision at file:line.
async function checkCollisionPlayback(page) {
  const doc = await reportJson(reportPath);
  if (!check(doc.playback != null, 'report has a playback')) return;
  const sample = int32s(doc.playback.frames.sample);
  const events = doc.events || [];
  const index = events.findIndex((e) => e.kind === 'machine_collision' && refCovers(e.line));
  if (!check(index >= 0, `a machine collision at ${wantFile}:${wantLine}`)) return;
  const e = events[index];
  // The frame of the collision's pose, from the data: the last frame at or before its sample.
  let frame = 0;
  while (frame + 1 < sample.length && sample[frame + 1] <= e.sample) frame++;
  const [a, b] = e.bodies;
  const boxes = () => page.evaluate(([x, y]) => [window.vcutPlayback.bodyBox(x), window.vcutPlayback.bodyBox(y)], [a, b]);

  await setSlider(page, 0);
  const [a0, b0] = await boxes();
  check(a0 && b0 && Math.min(...overlaps(a0, b0)) < 0, `at the first frame ${a} and ${b} are apart`);

  await setSlider(page, frame);
  const [a1, b1] = await boxes();
  const depth = Math.min(...overlaps(a1, b1));
  check(a1.visible && b1.visible, `both bodies shown at frame ${frame}`);
  check(Math.abs(depth - e.depth_mm) < 0.05,
    `at frame ${frame} ${a} is ${depth.toFixed(3)} mm into ${b} (vcut measured ${e.depth_mm.toFixed(3)} mm)`);
  const readout = await page.locator('#playback-readout').innerText();
  check(readout.includes(`${path.basename(wantFile)}:${wantLine}`), `the readout names ${wantFile}:${wantLine} ("${readout.replace(/\s+/g, ' ')}")`);

  // The machine's frame: the bed stands still from frame to frame (in the part's frame it
  // moves where the part turns: at the collision between two poses the table has turned).
  const frameBody = (await page.evaluate(() => window.vcutPlayback.bodyNames())).find((n) => /\(frame\)$/.test(n));
  const turned = await page.evaluate((i) => window.vcutPlayback.frameOfEvent(i),
    events.findIndex((x) => x.kind === 'machine_collision' && /between two poses/.test(x.detail || '')));
  if (check(frameBody != null && turned != null, `a body on the machine's frame (${frameBody}) and a frame where the table turned (${turned})`)) {
    const bedAt = async (k) => { await setSlider(page, k); return page.evaluate((n) => window.vcutPlayback.bodyBox(n), frameBody); };
    const moved = (p, q) => Math.max(...[0, 1, 2].map((k) => Math.abs(p.min[k] - q.min[k]) + Math.abs(p.max[k] - q.max[k])));
    const inPart = moved(await bedAt(0), await bedAt(turned));
    await page.locator('#toggle-machine-frame').click();
    const inMachine = moved(await bedAt(0), await bedAt(turned));
    await page.locator('#toggle-machine-frame').click();
    check(inPart > 1 && inMachine < 1e-3,
      `with the machine frame on, ${frameBody} stays put (moves ${inMachine.toExponential(1)} mm; in the part's frame ${inPart.toFixed(1)} mm)`);
  }

  // Next event from the start: the first event with a frame after 0.
  await setSlider(page, 0);
  await page.locator('#playback-next-event').click();
  const firstEvent = await page.evaluate(() => {
    const n = document.querySelectorAll('#event-table tbody tr').length;
    let best = null;
    for (let i = 0; i < n; i++) {
      const f = window.vcutPlayback.frameOfEvent(i);
      if (f != null && f > 0 && (best == null || f < best)) best = f;
    }
    return best;
  });
  const landed = await page.evaluate(() => window.vcutPlayback.frame());
  check(landed === firstEvent, `Next event lands on the first event's frame (${landed}, expected ${firstEvent})`);
  check((await page.locator('#event-table tr.selected').count()) === 1, 'Next event selects the event row');

  // A collision between two poses: clicking it poses the machine at that instant.
  const between = events.findIndex((x) => x.kind === 'machine_collision' && /between two poses/.test(x.detail || ''));
  if (check(between >= 0, 'the report has a collision between two poses')) {
    await page.locator(`#event-table tr[data-event-index="${between}"]`).click();
    await page.waitForFunction(() => window.vcutViewer.isAnimating() === false, null, { timeout: 10000, polling: 50 });
    const [x, y] = events[between].bodies;
    const [bx, by] = await page.evaluate(([p, q]) => [window.vcutPlayback.bodyBox(p), window.vcutPlayback.bodyBox(q)], [x, y]);
    check(await page.evaluate(() => window.vcutPlayback.atEvent()), 'the machine is shown at the event\'s instant');
    check(Math.min(...overlaps(bx, by)) > 0, `there ${x} and ${y} overlap (${overlaps(bx, by).map((v) => v.toFixed(2)).join(', ')} mm)`);
  }
}

// ---- the test ---------------------------------------------------------------------------

let chromium;
try {
  ({ chromium } = createRequire(path.join(webDir, 'package.json'))('playwright-core'));
} catch (e) {
  console.error(`cannot load playwright-core from ${webDir}/node_modules (run npm ci in web/): ${e.message}`);
  process.exit(1);
}

const failures = [];
const check = (ok, what) => {
  if (ok) console.log(`ok   ${what}`);
  else { console.log(`FAIL ${what}`); failures.push(what); }
  return ok;
};

const sameFile = (a, b) => a === b || path.basename(a) === path.basename(b);
function refCovers(ref) {
  const m = /^(.*):(\d+)(?:-(\d+))?$/.exec(String(ref).trim());
  if (!m || !sameFile(m[1], wantFile)) return false;
  const from = Number(m[2]);
  const to = m[3] != null ? Number(m[3]) : from;
  return wantLine >= from && wantLine <= to;
}

const consoleErrors = [];
const pageErrors = [];
const badRequests = new Set();
const allowedScheme = (url) => /^(file|data|blob):/i.test(url);

const browser = await chromium.launch({
  executablePath,
  headless: true,
  args: ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking', '--disable-quic',
    '--no-first-run', '--disable-component-update', '--disable-sync'],
});
let exitCode = 1;
try {
  const context = await browser.newContext({ viewport: { width: 1600, height: 1000 }, deviceScaleFactor: 1 });
  const page = await context.newPage();
  page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
  page.on('pageerror', (e) => pageErrors.push(String(e && e.stack ? e.stack : e)));
  page.on('request', (r) => { if (!allowedScheme(r.url())) badRequests.add(r.url()); });
  page.on('websocket', (ws) => badRequests.add(ws.url()));
  await context.route('**/*', (route) => {
    const url = route.request().url();
    if (allowedScheme(url)) return route.continue();
    badRequests.add(url);
    return route.abort('blockedbyclient');
  });

  await page.goto(pathToFileURL(reportPath).href, { waitUntil: 'load', timeout: READY_TIMEOUT_MS });
  let ready = false;
  try {
    await page.waitForFunction(() => window.vcutReady === true || typeof window.vcutError === 'string',
      null, { timeout: READY_TIMEOUT_MS, polling: 100 });
    ready = await page.evaluate(() => window.vcutReady === true);
  } catch (e) {
    // timed out: reported below
  }
  const pageError = await page.evaluate(() => window.vcutError || null);
  check(ready, `page ready (window.vcutReady)${pageError ? `: page reports "${pageError}"` : ''}`);

  if (ready && collisionMode) {
    await checkCollisionPlayback(page);
  } else if (ready) {
    const rows = await page.$$eval('#gouge-table tbody tr[data-kind="gouge"]', (trs) =>
      trs.map((tr) => ({ index: Number(tr.getAttribute('data-region-index')), lines: tr.getAttribute('data-lines') || '' })));
    const regions = await readRegions(reportPath);
    let rowIndex = -1;
    for (let k = 0; k < rows.length; k++) {
      const r = regions[rows[k].index];
      const refs = r && Array.isArray(r.lines) ? r.lines : rows[k].lines.split(/\s+/);
      if (refs.some(refCovers)) { rowIndex = k; break; }
    }
    if (check(rowIndex >= 0, `gouge table has a row for ${lineArg} (${rows.length} gouge rows)`)) {
      const region = regions[rows[rowIndex].index];
      const before = await page.evaluate(() => window.vcutViewer.cameraState());
      await page.locator('#gouge-table tbody tr[data-kind="gouge"]').nth(rowIndex).click();
      await page.waitForTimeout(50);
      await page.waitForFunction(() => window.vcutViewer.isAnimating() === false, null, { timeout: 10000, polling: 50 });
      const after = await page.evaluate(() => window.vcutViewer.cameraState());
      const deepest = region.deepest || region.centroid;
      const dist = (a, b) => Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
      if (check(Array.isArray(deepest) && deepest.length === 3, 'region has a deepest point in the data')) {
        const d = dist(after.target, deepest);
        check(d <= TARGET_TOLERANCE_MM, `camera target at the deepest point (${d.toExponential(2)} mm away)`);
      }
      check(dist(before.position, after.position) > 1e-6, 'camera position changed');

      const text = ncText(region, regions, wantFile, wantLine, await readSources(reportPath));
      if (check(text != null, `data gives the text of ${lineArg}`)) {
        const panel = await page.locator('#nc-panel').innerText();
        check(panel.includes(text.trim()), `NC panel shows "${text.trim()}"`);
        check(panel.includes(String(wantLine)), `NC panel shows line number ${wantLine}`);
      }
    }

    await checkPlayback(page);
  }
  if (ready) {
    // Let the frame with the marker land, then capture.
    await page.waitForTimeout(200);
    await page.screenshot({ path: shotArg, fullPage: true });
    // Hide the HTML overlays (toolbar, legend, labels) so only WebGL pixels are judged.
    await page.addStyleTag({ content: '#viewport > :not(canvas) { visibility: hidden !important; }' });
    const canvasPng = await page.locator('#viewport canvas').first().screenshot();
    const stats = await imageStats(page, canvasPng);
    check(stats.distinct >= 64 && stats.dominantShare < 0.97,
      `WebGL canvas drew an image (${stats.distinct} distinct colours, dominant ${(stats.dominantShare * 100).toFixed(1)} %)`);
  } else {
    await page.screenshot({ path: shotArg, fullPage: true }).catch(() => {});
  }

  check(pageErrors.length === 0, `no page errors${pageErrors.length ? `: ${pageErrors.join(' | ')}` : ''}`);
  check(consoleErrors.length === 0, `no console errors${consoleErrors.length ? `: ${consoleErrors.join(' | ')}` : ''}`);
  check(badRequests.size === 0, `no network requests${badRequests.size ? `: ${[...badRequests].join(' ')}` : ''}`);
  exitCode = failures.length === 0 ? 0 : 1;
} catch (e) {
  console.log(`FAIL test error: ${e && e.stack ? e.stack : e}`);
  exitCode = 1;
} finally {
  await browser.close().catch(() => {});
}
if (exitCode === 0) console.log(`PASS (screenshot ${shotArg})`);
else console.log(`${failures.length || 1} check(s) failed`);
process.exit(exitCode);
