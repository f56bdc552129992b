// Builds the self-contained report template: node web/build.mjs OUT.html
// Bundles web/src (esbuild, IIFE, minified), inlines the JS and CSS into web/src/page.html
// and writes OUT.html (via OUT.html.tmp + rename). The template keeps exactly one
// occurrence of the data marker, which the vcut CLI replaces with the report JSON.

import { build } from 'esbuild';
import { readFile, writeFile, rename, mkdir, unlink } from 'node:fs/promises';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const MARKER = '__VCUT_REPORT_DATA__';
const here = path.dirname(fileURLToPath(import.meta.url));

function die(msg) {
  console.error(`build.mjs: ${msg}`);
  process.exit(1);
}

const out = process.argv[2];
if (!out || process.argv.length > 3) {
  console.error('usage: node web/build.mjs OUT.html');
  process.exit(2);
}

const result = await build({
  absWorkingDir: here,
  entryPoints: [path.join(here, 'src', 'main.js')],
  bundle: true,
  format: 'iife',
  minify: true,
  platform: 'browser',
  target: ['chrome100', 'firefox100', 'safari15.4', 'edge100'],
  charset: 'utf8',
  legalComments: 'inline',
  outdir: 'out', // nothing is written: write is false
  write: false,
  logLevel: 'warning',
});
let js = '';
let css = '';
for (const f of result.outputFiles) {
  if (f.path.endsWith('.js')) js += f.text;
  else if (f.path.endsWith('.css')) css += f.text;
}
if (!js) die('esbuild produced no JavaScript');

// Inline <script>/<style> content must not close its element early or open an HTML comment
// (which changes how the parser looks for the closing tag).
if (/<\/script/i.test(js)) die('bundled JS contains "</script"');
if (/<!--/.test(js)) js = js.replace(/<!--/g, '\\x3C!--');
if (/<!--/.test(js)) die('bundled JS contains "<!--"');
if (/<\/style/i.test(css)) die('bundled CSS contains "</style"');
if (js.includes(MARKER) || css.includes(MARKER)) die(`bundle contains the data marker ${MARKER}`);

const page = await readFile(path.join(here, 'src', 'page.html'), 'utf8');
const STYLE_SLOT = '/*VCUT_STYLE*/';
const SCRIPT_SLOT = '/*VCUT_SCRIPT*/';
for (const slot of [STYLE_SLOT, SCRIPT_SLOT]) {
  if (page.split(slot).length !== 2) die(`page.html must contain ${slot} exactly once`);
}
// split/join, not String.replace: the bundle contains "$&"-like sequences.
const html = page.split(STYLE_SLOT).join(css.trim()).split(SCRIPT_SLOT).join(js.trim());

const markerCount = html.split(MARKER).length - 1;
if (markerCount !== 1) die(`template contains the data marker ${markerCount} times, expected exactly 1`);
const slot = `<script id="vcut-data" type="application/json">${MARKER}</script>`;
if (!html.includes(slot)) die(`template lacks ${slot}`);

const outPath = path.resolve(out);
await mkdir(path.dirname(outPath), { recursive: true });
const tmp = `${outPath}.tmp`;
try {
  await writeFile(tmp, html, 'utf8');
  await rename(tmp, outPath);
} catch (e) {
  await unlink(tmp).catch(() => {});
  die(`cannot write ${outPath}: ${e.message}`);
}
console.log(`wrote ${out} (${(Buffer.byteLength(html) / 1024).toFixed(1)} KiB: JS ${(Buffer.byteLength(js) / 1024).toFixed(1)} KiB, CSS ${(Buffer.byteLength(css) / 1024).toFixed(1)} KiB)`);
