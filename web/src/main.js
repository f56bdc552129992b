// vcut report page: reads the JSON the vcut CLI put into <script id="vcut-data"> and builds
// the summary, the 3D view, the region/event tables, the NC panel and the charts.
// Data contract: web/README.md (schema "vcut-report-page/1").

import './style.css';
import { decodeMesh } from './decode.js';
import { Viewer } from './viewer.js';
import { decodePlayback, orderTrianglesByBlock, Playback, playbackBar } from './playback.js';
import { histogramChart, lineChart, emptyChart } from './charts.js';
import { makeScale, deviationColor, cssColor } from './colormap.js';
import {
  el, num, sig, mm, signedMm, duration, volume, xyz, isNum, parseLineRef, basename,
} from './format.js';

const SCHEMA = 'vcut-report-page/1';

const EVENT_LABELS = {
  rapid_into_stock: 'Rapid into stock',
  holder_collision: 'Holder collision',
  shank_collision: 'Shank collision',
  spindle_off_cut: 'Cut with spindle off',
  axis_limit: 'Axis limit',
  singular: 'Singular pose',
  unreachable: 'Unreachable pose',
  axis_limited_speed: 'Axis-limited speed',
  densify_error: 'Densified off the machine path',
  machine_collision: 'Machine collision',
  machine_near_miss: 'Machine near miss',
};
const SEVERE_EVENTS = new Set(['rapid_into_stock', 'holder_collision', 'shank_collision', 'spindle_off_cut', 'axis_limit', 'unreachable', 'machine_collision']);

function fail(title, detail) {
  window.vcutError = `${title}${detail ? `: ${detail}` : ''}`;
  const app = document.getElementById('app');
  app.replaceChildren(el('div', { class: 'fatal' },
    el('div', { class: 'fatal-box' },
      el('div', { class: 'brand' }, 'vcut'),
      el('h1', { text: title }),
      detail ? el('p', { text: detail }) : null)));
}

function readData() {
  const node = document.getElementById('vcut-data');
  const text = node ? node.textContent.trim() : '';
  // The template marker is never spelled out here: the build checks it occurs exactly once.
  if (/^__VCUT_REPORT_[A-Z]+__$/.test(text)) {
    fail('This is the empty vcut report template',
      'No simulation data has been filled in. vcut writes a complete report.html next to report.json when it simulates a job; open that file instead.');
    return null;
  }
  if (!text) {
    fail('No report data', 'The page has no <script id="vcut-data"> content.');
    return null;
  }
  try {
    const d = JSON.parse(text);
    if (node) node.textContent = ''; // drop the (possibly huge) text once parsed
    return d;
  } catch (e) {
    fail('The report data could not be read', String(e && e.message ? e.message : e));
    return null;
  }
}

// ---- NC line lookup ---------------------------------------------------------------------

class NcIndex {
  constructor(data) {
    this.text = new Map();
    const add = (e) => {
      if (e && e.file != null && isNum(e.line) && typeof e.text === 'string') this.text.set(`${e.file}:${e.line}`, e.text);
    };
    (data.sources || []).forEach(add);
    for (const r of data.regions || []) (r.nc || []).forEach(add);
    for (const e of data.events || []) (e.nc || []).forEach(add);
  }

  lookup(file, line) {
    return this.text.get(`${file}:${line}`);
  }

  // NC entries for a record: its own nc list, completed from the refs in `lines`.
  entriesFor(lines, nc) {
    const out = [];
    const seen = new Set();
    for (const e of nc || []) {
      const k = `${e.file}:${e.line}`;
      if (seen.has(k)) continue;
      seen.add(k);
      out.push({ file: e.file, line: e.line, text: e.text });
    }
    for (const ref of lines || []) {
      const p = parseLineRef(ref);
      if (!p) continue;
      const span = p.to - p.from;
      for (let l = p.from; l <= p.to && l - p.from < 200; l++) {
        const k = `${p.file}:${l}`;
        if (seen.has(k)) continue;
        const t = this.lookup(p.file, l);
        if (t == null && span > 0) continue; // a range: list only lines whose text we have
        seen.add(k);
        out.push({ file: p.file, line: l, text: t });
      }
    }
    return out;
  }
}

// ---- page pieces -----------------------------------------------------------------------

function card(label, value, sub, tone) {
  return el('div', { class: `card${tone ? ` tone-${tone}` : ''}` },
    el('div', { class: 'card-label', text: label }),
    el('div', { class: 'card-value', text: value }),
    sub ? el('div', { class: 'card-sub', text: sub }) : null);
}

function linesCell(lines) {
  const list = lines || [];
  const shown = list.slice(0, 3);
  return el('td', { class: 'lines', title: list.join('\n') },
    shown.join(', '),
    list.length > shown.length ? el('span', { class: 'more', text: ` +${list.length - shown.length}` }) : null);
}

function sectionTitle(text, count) {
  return el('div', { class: 'section-title' }, el('span', { text }), count != null ? el('span', { class: 'count', text: String(count) }) : null);
}

function verdict(data, gouges, excess, severeEvents) {
  if (gouges.length > 0) return { tone: 'bad', text: `${gouges.length} gouge${gouges.length > 1 ? 's' : ''} beyond tolerance` };
  if (severeEvents > 0) return { tone: 'bad', text: `${severeEvents} event${severeEvents > 1 ? 's' : ''} to review` };
  if (!data.design) return { tone: 'info', text: 'No design comparison' };
  if (excess.length > 0) return { tone: 'warn', text: `${excess.length} excess region${excess.length > 1 ? 's' : ''}` };
  return { tone: 'good', text: 'Within tolerance' };
}

const timings = {};
let lastMark = performance.now();
const mark = (name) => {
  const now = performance.now();
  timings[name] = Math.round(now - lastMark);
  lastMark = now;
};
window.vcutTimings = timings; // ms per load stage, for PERFORMANCE notes and debugging

function main() {
  mark('start');
  const data = readData();
  mark('parse');
  if (!data) return;
  if (data.schema && data.schema !== SCHEMA) {
    console.warn(`vcut report: schema ${data.schema}, page expects ${SCHEMA}; showing what it can`);
  }
  const job = data.job || {};
  const summary = data.summary || {};
  const regions = Array.isArray(data.regions) ? data.regions : [];
  const events = Array.isArray(data.events) ? data.events : [];
  const gouges = [];
  const excess = [];
  regions.forEach((r, i) => (r.kind === 'gouge' ? gouges : excess).push([r, i]));
  const severeEvents = events.filter((e) => SEVERE_EVENTS.has(e.kind)).length;
  const gougeTol = isNum(job.gouge_tolerance_mm) ? job.gouge_tolerance_mm : 0.02;
  const excessTol = isNum(job.excess_tolerance_mm) ? job.excess_tolerance_mm : 0.1;
  const scale = makeScale(gougeTol, excessTol);
  const nc = new NcIndex(data);
  const title = data.title || job.name || 'vcut report';
  document.title = `${title} · vcut report`;

  // Header and summary.
  const v = verdict(data, gouges, excess, severeEvents);
  const header = el('header', { class: 'top' },
    el('div', { class: 'brand', text: 'vcut' }),
    el('div', { class: 'title-block' },
      el('h1', { text: title }),
      el('div', { class: 'subtitle' },
        [job.file, job.machine && `machine ${job.machine}`, job.engine && `${job.engine} engine`,
          isNum(job.resolution_mm) && `resolution ${num(job.resolution_mm, 3)} mm`,
          isNum(job.threads) && `${job.threads} thread${job.threads > 1 ? 's' : ''}`].filter(Boolean).join('  ·  '))),
    el('div', { class: `verdict tone-${v.tone}`, id: 'verdict', text: v.text }));

  const firstGouge = gouges[0] && gouges[0][0];
  const firstExcess = excess[0] && excess[0][0];
  const maxGouge = isNum(summary.max_gouge_mm) ? summary.max_gouge_mm : firstGouge ? firstGouge.depth_mm : null;
  const maxExcess = isNum(summary.max_excess_mm) ? summary.max_excess_mm : firstExcess ? firstExcess.depth_mm : null;
  const removedPct = isNum(summary.removed_volume_mm3) && summary.initial_volume_mm3 > 0
    ? `${num((100 * summary.removed_volume_mm3) / summary.initial_volume_mm3, 1)} % of the stock` : null;
  const cards = el('section', { class: 'cards' },
    card('Max gouge', data.design ? mm(maxGouge) : '–',
      data.design ? (firstGouge ? `at ${(firstGouge.lines || [])[0] || '?'}` : `tolerance ${num(gougeTol, 3)} mm`) : 'no design given',
      data.design ? (isNum(maxGouge) && maxGouge > gougeTol ? 'bad' : 'good') : null),
    card('Max excess', data.design ? mm(maxExcess) : '–',
      data.design ? (firstExcess ? `at ${(firstExcess.lines || [])[0] || '?'}` : `tolerance ${num(excessTol, 3)} mm`) : 'no design given',
      data.design ? (isNum(maxExcess) && maxExcess > excessTol ? 'warn' : 'good') : null),
    card('Removed volume', volume(summary.removed_volume_mm3), removedPct),
    card('Cycle time', duration(summary.cycle_time_s), isNum(summary.cutting_moves) ? `${num(summary.cutting_moves)} cutting moves` : null),
    card('Events', String(events.length), severeEvents ? `${severeEvents} severe` : events.length ? 'none severe' : 'none', severeEvents ? 'bad' : events.length ? 'warn' : 'good'),
    card('Wall time', duration(summary.wall_time_s), isNum(job.threads) ? `${job.threads} thread${job.threads > 1 ? 's' : ''}` : null),
    card('Peak memory', isNum(summary.peak_memory_mb) ? `${num(summary.peak_memory_mb)} MB` : '–',
      isNum(summary.blocks) ? `${num(summary.blocks)} blocks, ${num(summary.moves)} moves` : null));

  // 3D view and its overlays.
  const viewport = el('div', { class: 'viewport', id: 'viewport' });
  const toolbar = el('div', { class: 'toolbar' });
  const legend = el('div', { class: 'legend', id: 'legend' });
  const pickHint = el('div', { class: 'hint' },
    'Left drag: orbit · Right drag: pan · Wheel: zoom · Click: inspect · Double-click: centre');
  viewport.append(toolbar, legend, pickHint);

  const ncPanel = el('div', { class: 'panel nc-panel', id: 'nc-panel' });
  const side = el('aside', { class: 'side' }, ncPanel);
  const work = el('main', { class: 'work' }, viewport, side);

  // Warnings (undeclared M codes, stops, nested comments ...): each names its file:line.
  const warnings = Array.isArray(data.warnings) ? data.warnings : [];
  const warningList = warnings.length
    ? el('section', { class: 'warnings', id: 'warnings' },
      el('h2', { text: `Warnings (${warnings.length})` }),
      el('ul', {}, ...warnings.slice(0, 200).map((w) => el('li', { text: String(w) }))),
      warnings.length > 200 ? el('p', { text: `… and ${warnings.length - 200} more in report.json` }) : null)
    : null;

  // A program simulated without a job file: what vcut assumed (machine, stock, tools), first.
  const assumptions = Array.isArray(data.assumptions) ? data.assumptions : [];
  const assumptionList = assumptions.length
    ? el('section', { class: 'warnings assumptions', id: 'assumptions' },
      el('h2', { text: `Assumed, with no job file (${assumptions.length}): check these` }),
      el('ul', {}, ...assumptions.map((a) => el('li', { text: String(a) }))))
    : null;

  const app = document.getElementById('app');
  app.replaceChildren(...[header, cards, assumptionList, warningList, work].filter(Boolean));

  // NC panel content.
  const showNc = (heading, facts, entries, emptyNote) => {
    const body = [];
    body.push(el('div', { class: 'panel-title' }, heading));
    if (facts && facts.length) {
      body.push(el('dl', { class: 'facts' }, facts.flatMap(([k, val]) => [el('dt', { text: k }), el('dd', { text: val })])));
    }
    if (entries && entries.length) {
      body.push(el('div', { class: 'nc-list' }, entries.map((e) => el('div', { class: 'nc-line', 'data-ref': `${e.file}:${e.line}` },
        el('span', { class: 'nc-ref', text: `${basename(e.file)}:${e.line}`, title: `${e.file}:${e.line}` }),
        el('code', { class: 'nc-text', text: e.text != null ? e.text : '(text not in report)' })))));
    } else if (emptyNote) {
      body.push(el('div', { class: 'muted', text: emptyNote }));
    }
    ncPanel.replaceChildren(...body);
  };
  showNc('NC lines', null, null,
    regions.length || events.length ? 'Click a gouge, excess region or event, or click on the part, to see its NC lines here.'
      : 'Click on the part to see the deviation and the NC line that cut it.');

  // Tables.
  let selectedRow = null;
  const select = (row) => {
    if (selectedRow) selectedRow.classList.remove('selected');
    selectedRow = row;
    if (row) row.classList.add('selected');
  };

  let viewer = null;
  let playback = null;
  const eventActivators = [];
  const regionTable = (kind, list) => {
    const wrap = el('div', { class: 'table-block' });
    wrap.append(sectionTitle(kind === 'gouge' ? 'Gouges' : 'Excess material', list.length));
    if (!data.design) {
      wrap.append(el('div', { class: 'muted small', text: 'No design part in the job: no comparison.' }));
      return wrap;
    }
    if (list.length === 0) {
      wrap.append(el('div', { class: 'muted small', text: kind === 'gouge' ? `No gouge deeper than ${num(gougeTol, 3)} mm.` : `No excess above ${num(excessTol, 3)} mm.` }));
      return wrap;
    }
    const tbody = el('tbody');
    list.forEach(([r, idx], k) => {
      const tools = (r.tools || []).map((t) => `T${t}`).join(' ');
      const sw = cssColor(deviationColor(kind === 'gouge' ? -Math.abs(r.depth_mm) : Math.abs(r.depth_mm), scale));
      const row = el('tr', {
        class: `row-${kind}`, 'data-kind': kind, 'data-lines': (r.lines || []).join(' '),
        'data-region-index': idx, tabindex: 0, title: 'Show on the part',
      },
      el('td', { class: 'idx' }, el('span', { class: 'swatch', style: `background:${sw}` }), String(k + 1)),
      el('td', { class: 'numc', text: num(r.depth_mm, 3) }),
      el('td', { class: 'numc', text: sig(r.area_mm2, 3) }),
      linesCell(r.lines),
      el('td', { text: r.initial_stock ? `${tools}${tools ? ' ' : ''}stock` : tools || '–' }));
      const activate = () => {
        select(row);
        const facts = [
          [kind === 'gouge' ? 'Depth' : 'Excess', mm(r.depth_mm, 4)],
          ['Area', isNum(r.area_mm2) ? `${sig(r.area_mm2, 3)} mm²` : '–'],
          ['Deepest', xyz(r.deepest)],
          ['Tools', tools || '–'],
        ];
        if (r.initial_stock) facts.push(['Surface', 'initial stock, never cut']);
        showNc(`${kind === 'gouge' ? 'Gouge' : 'Excess'} ${k + 1}`, facts, nc.entriesFor(r.lines, r.nc),
          r.initial_stock ? 'Never cut: no NC line.' : 'No NC line recorded.');
        const p = r.deepest || r.centroid;
        if (viewer && p) { viewer.setMarker(p); viewer.flyTo(p); }
      };
      row.addEventListener('click', activate);
      row.addEventListener('keydown', (e) => { if (e.key === 'Enter' || e.key === ' ') { e.preventDefault(); activate(); } });
      tbody.append(row);
    });
    wrap.append(el('div', { class: 'table-scroll' }, el('table', { class: 'grid-table', id: `${kind}-table` },
      el('thead', null, el('tr', null, el('th', { text: '#' }), el('th', { class: 'numc', text: kind === 'gouge' ? 'Depth mm' : 'Excess mm' }),
        el('th', { class: 'numc', text: 'Area mm²' }), el('th', { text: 'NC lines' }), el('th', { text: 'Tool' }))),
      tbody)));
    return wrap;
  };

  const eventTable = () => {
    const wrap = el('div', { class: 'table-block' });
    wrap.append(sectionTitle('Events', events.length));
    if (events.length === 0) {
      wrap.append(el('div', { class: 'muted small', text: 'No collisions, limits or other events.' }));
      return wrap;
    }
    const tbody = el('tbody');
    events.forEach((e, i) => {
      const label = EVENT_LABELS[e.kind] || String(e.kind || 'event');
      const row = el('tr', {
        class: `row-event${SEVERE_EVENTS.has(e.kind) ? ' severe' : ''}`, 'data-kind': e.kind, 'data-lines': e.line || '',
        'data-event-index': i, tabindex: 0,
      },
      el('td', { class: 'nowrap' }, el('span', { class: `ev-dot${SEVERE_EVENTS.has(e.kind) ? ' severe' : ''}` }), label),
      el('td', { class: 'lines nowrap', text: e.line || '–' }),
      el('td', { class: 'numc', text: isNum(e.depth_mm) ? num(e.depth_mm, 3) : '–' }),
      el('td', { class: 'detail', text: e.detail || '', title: e.detail || '' }));
      const activate = () => {
        select(row);
        const facts = [['Line', e.line || '–']];
        if (isNum(e.depth_mm)) facts.push(['Depth', mm(e.depth_mm, 4)]);
        if (e.where) facts.push(['Where', xyz(e.where)]);
        if (e.detail) facts.push(['Detail', e.detail]);
        showNc(label, facts, nc.entriesFor(e.line ? [e.line] : [], e.nc), 'No NC line recorded.');
        if (playback) playback.showEvent(i);
        if (viewer) {
          if (Array.isArray(e.where)) { viewer.setMarker(e.where); viewer.flyTo(e.where); } else viewer.setMarker(null);
        }
      };
      eventActivators[i] = activate;
      row.addEventListener('click', activate);
      row.addEventListener('keydown', (ev) => { if (ev.key === 'Enter' || ev.key === ' ') { ev.preventDefault(); activate(); } });
      tbody.append(row);
    });
    wrap.append(el('div', { class: 'table-scroll' }, el('table', { class: 'grid-table', id: 'event-table' },
      el('thead', null, el('tr', null, el('th', { text: 'Event' }), el('th', { text: 'Line' }), el('th', { class: 'numc', text: 'Depth mm' }), el('th', { text: 'Detail' }))),
      tbody)));
    return wrap;
  };
  side.append(el('div', { class: 'panel tables' }, regionTable('gouge', gouges), regionTable('excess', excess), eventTable()));

  // Charts and job tables below the workspace.
  const charts = el('section', { class: 'charts' });
  const chartCard = (t, body, note) => el('div', { class: 'panel chart-card' },
    el('div', { class: 'section-title' }, el('span', { text: t })), body, note ? el('div', { class: 'chart-note', text: note }) : null);
  charts.append(chartCard('Deviation histogram',
    data.histogram ? histogramChart(data.histogram, scale) : emptyChart(data.design ? 'No histogram in this report.' : 'No design part: no deviation.'),
    data.histogram ? `Bars coloured as on the part: neutral from −${num(gougeTol, 3)} to +${num(scale.excessStart, 3)} mm, full red at −${num(scale.gougeFull, 3)} mm, full blue at +${num(scale.excess, 3)} mm. Hover a bar for its counts.` : null));
  const tl = data.timeline;
  charts.append(chartCard('Feed over time',
    tl && tl.t_s && tl.feed_mm_min ? lineChart({ xs: tl.t_s, ys: tl.feed_mm_min, title: 'Feed', yLabel: 'feed (mm/min)', xLabel: 'time (s)', color: '#2f7dd1', unit: 'mm/min' })
      : emptyChart('No timeline in this report.')));
  charts.append(chartCard('Contour error over time',
    tl && tl.t_s && tl.contour_error_um ? lineChart({ xs: tl.t_s, ys: tl.contour_error_um, title: 'Contour error', yLabel: 'contour error (µm)', xLabel: 'time (s)', color: '#d9632b', unit: 'µm', decimals: 2 })
      : emptyChart(tl ? 'No contour error computed (no servo model in the job).' : 'No timeline in this report.')));

  const settingsRows = [];
  const addSetting = (k, val) => { if (val != null && val !== '') settingsRows.push([k, String(val)]); };
  addSetting('Job', job.name);
  addSetting('Job file', job.file);
  addSetting('Machine', job.machine);
  addSetting('Engine', job.engine);
  if (isNum(job.resolution_mm)) addSetting('Resolution', `${num(job.resolution_mm, 3)} mm`);
  if (isNum(job.threads)) addSetting('Threads', job.threads);
  if (isNum(job.gouge_tolerance_mm)) addSetting('Gouge tolerance', `${num(job.gouge_tolerance_mm, 3)} mm`);
  if (isNum(job.excess_tolerance_mm)) addSetting('Excess tolerance', `${num(job.excess_tolerance_mm, 3)} mm`);
  if (isNum(job.collision_tolerance_mm)) addSetting('Collision tolerance', `${num(job.collision_tolerance_mm, 3)} mm`);
  for (const row of job.settings || []) if (Array.isArray(row) && row.length >= 2) addSetting(row[0], row[1]);

  const settingsTable = el('table', { class: 'kv-table', id: 'settings-table' },
    el('tbody', null, settingsRows.map(([k, val]) => el('tr', null, el('th', { text: k }), el('td', { text: val })))));

  const stages = (summary.stage_seconds || []).filter((s) => Array.isArray(s) && isNum(s[1]));
  const stageTotal = stages.reduce((a, s) => a + s[1], 0);
  const stageMax = Math.max(1e-9, ...stages.map((s) => s[1]));
  const timingTable = stages.length
    ? el('table', { class: 'kv-table timing', id: 'timing-table' }, el('tbody', null,
      stages.map(([k, s]) => el('tr', null, el('th', { text: k }), el('td', { class: 'numc', text: duration(s) }),
        el('td', { class: 'barcell' }, el('div', { class: 'hbar', style: `width:${((100 * s) / stageMax).toFixed(1)}%` })),
        el('td', { class: 'numc muted', text: stageTotal > 0 ? `${num((100 * s) / stageTotal, 1)} %` : '' }))),
      el('tr', { class: 'total' }, el('th', { text: 'total' }), el('td', { class: 'numc', text: duration(stageTotal) }), el('td'), el('td'))))
    : el('div', { class: 'muted small', text: 'No stage timings.' });

  const figures = [
    ['NC blocks', num(summary.blocks)], ['Moves', num(summary.moves)], ['Cutting moves', num(summary.cutting_moves)],
    ['Initial volume', volume(summary.initial_volume_mm3)], ['Removed volume', volume(summary.removed_volume_mm3)],
    ['Cycle time', duration(summary.cycle_time_s)], ['Wall time', duration(summary.wall_time_s)],
    ['Peak memory', isNum(summary.peak_memory_mb) ? `${num(summary.peak_memory_mb)} MB` : '–'],
    ['Triangles shown', isNum(summary.triangles_shown) ? num(summary.triangles_shown) : '–'],
    ['Triangles machined', isNum(summary.triangles_machined) ? num(summary.triangles_machined) : '–'],
  ];
  const figuresTable = el('table', { class: 'kv-table', id: 'figures-table' },
    el('tbody', null, figures.map(([k, val]) => el('tr', null, el('th', { text: k }), el('td', { class: 'numc', text: val })))));

  const lower = el('section', { class: 'lower' },
    el('div', { class: 'panel' }, sectionTitle('Job settings'), settingsTable),
    el('div', { class: 'panel' }, sectionTitle('Figures'), figuresTable),
    el('div', { class: 'panel' }, sectionTitle('Timings'), timingTable));
  const footer = el('footer', { class: 'foot' },
    `vcut report · ${data.schema || SCHEMA} · lengths in mm, times in s · self-contained page, no network access`);
  app.append(charts, lower, footer);
  mark('page');

  // Mesh decoding and the 3D view last: the tables are usable even if WebGL fails.
  let model;
  let partKeys = null;
  // A damaged playback leaves the rest of the view as it is.
  let pb = null;
  let playbackError = null;
  try {
    pb = data.playback ? decodePlayback(data.playback) : null;
  } catch (e) {
    playbackError = e.message;
    console.warn(`vcut report: the playback data is damaged (${e.message}); no playback`);
  }
  try {
    model = {
      mesh: data.mesh ? decodeMesh(data.mesh, 'mesh') : null,
      design: data.design ? decodeMesh(data.design, 'design') : null,
      stock: data.stock ? (data.stock.mesh ? { mesh: decodeMesh(data.stock.mesh, 'stock.mesh') } : data.stock) : null,
      regions,
      gougeTol,
      excessTol,
      playback: pb,
    };
    // The part drawn up to the playback's block: its triangles in the order the blocks cut them.
    if (pb && model.mesh) partKeys = orderTrianglesByBlock(model.mesh);
    mark('decode');
  } catch (e) {
    viewport.append(el('div', { class: 'view-error', text: `The mesh data is damaged: ${e.message}` }));
    window.vcutError = `mesh data: ${e.message}`;
    return;
  }

  try {
    viewer = new Viewer(viewport, model, (hit) => {
      select(null);
      if (!hit) { viewer.setMarker(null); return; }
      viewer.setMarker(hit.point);
      const srcIndex = hit.source;
      const src = isNum(srcIndex) && srcIndex >= 0 && data.sources ? data.sources[srcIndex] : null;
      const dev = hit.deviation;
      let state = 'no design';
      if (isNum(dev)) state = dev < -gougeTol ? 'gouge' : dev > excessTol ? 'excess' : 'within tolerance';
      const facts = [
        ['Point', xyz(hit.point)],
        ['Deviation', isNum(dev) ? `${signedMm(dev, 4)} (${state})` : 'n/a'],
        ['Cut by', src ? `${src.file}:${src.line}` : srcIndex === -1 ? 'initial stock, never cut' : 'unknown'],
      ];
      showNc('Picked point', facts, src ? [src] : [], srcIndex === -1 ? 'This surface was never cut.' : null);
    });
  } catch (e) {
    const msg = `WebGL is not available, so the 3D view cannot be shown (${e && e.message ? e.message : e}). The tables and charts below still work.`;
    viewport.append(el('div', { class: 'view-error', text: msg }));
    legend.classList.add('hidden');
    pickHint.classList.add('hidden');
    window.vcutError = `WebGL: ${e && e.message ? e.message : e}`;
    console.error('vcut report:', msg);
    return;
  }

  // Toolbar.
  const toggle = (label, on, enabled, fn, id) => {
    const b = el('button', { type: 'button', class: `tool${on ? ' on' : ''}`, id, disabled: !enabled, 'aria-pressed': String(!!on), text: label });
    b.addEventListener('click', () => {
      const now = !b.classList.contains('on');
      b.classList.toggle('on', now);
      b.setAttribute('aria-pressed', String(now));
      fn(now);
    });
    return b;
  };
  const viewBtn = (label, name) => {
    const b = el('button', { type: 'button', class: 'tool view', text: label, title: `${label} view` });
    b.addEventListener('click', () => viewer.setView(name));
    return b;
  };
  toolbar.append(
    el('div', { class: 'tool-group' },
      toggle('Deviation colours', viewer.hasDeviation, viewer.hasDeviation, (on) => { viewer.setColorByDeviation(on); legend.classList.toggle('hidden', !on); }, 'toggle-deviation'),
      toggle('Design', false, !!viewer.design, (on) => viewer.setDesignVisible(on), 'toggle-design'),
      toggle('Initial stock', false, !!viewer.stock, (on) => viewer.setStockVisible(on), 'toggle-stock'),
      toggle('Region markers', !!viewer.regionPoints, !!viewer.regionPoints, (on) => viewer.setRegionMarkersVisible(on), 'toggle-markers')),
    el('div', { class: 'tool-group' }, viewBtn('Iso', 'iso'), viewBtn('Top', 'top'), viewBtn('Front', 'front'), viewBtn('Right', 'right')));

  // Legend.
  if (viewer.hasDeviation) {
    const s = scale;
    // Piecewise-linear legend axis: full excess on top, full gouge at the bottom.
    const stops = [[0, s.excess * 1.4], [0.12, s.excess], [0.38, s.excessStart], [0.5, 0], [0.62, -s.gouge], [0.88, -s.gougeFull], [1, -s.gougeFull * 1.4]];
    const valueAt = (f) => {
      for (let i = 1; i < stops.length; i++) {
        if (f <= stops[i][0]) {
          const [f0, v0] = stops[i - 1];
          const [f1, v1] = stops[i];
          return v0 + ((f - f0) / (f1 - f0)) * (v1 - v0);
        }
      }
      return stops[stops.length - 1][1];
    };
    const grad = [];
    for (let i = 0; i <= 40; i++) grad.push(`${cssColor(deviationColor(valueAt(i / 40), s))} ${(i * 2.5).toFixed(1)}%`);
    const bar = el('div', { class: 'legend-bar', style: `background:linear-gradient(to bottom, ${grad.join(',')})` });
    const labels = el('div', { class: 'legend-labels' },
      [[0.12, `+${num(s.excess, 3)}`, 'excess tolerance'], [0.38, `+${num(s.excessStart, 3)}`, ''], [0.5, '0', ''],
        [0.62, `−${num(s.gouge, 3)}`, 'gouge tolerance'], [0.88, `−${num(s.gougeFull, 3)}`, '3 × gouge tolerance']]
        .map(([f, t, tip]) => el('div', { class: 'legend-label', style: `top:${(f * 100).toFixed(1)}%`, title: tip, text: t })));
    legend.append(el('div', { class: 'legend-title', text: 'Deviation mm' }),
      el('div', { class: 'legend-body' }, bar, labels),
      el('div', { class: 'legend-keys' },
        el('div', null, el('span', { class: 'key', style: `background:${cssColor(deviationColor(1e9, s))}` }), 'excess'),
        el('div', null, el('span', { class: 'key', style: `background:${cssColor(deviationColor(-1e9, s))}` }), 'gouge'),
        el('div', null, el('span', { class: 'key', style: `background:${cssColor(deviationColor(NaN, s))}` }), 'no design')));
  } else {
    legend.classList.add('hidden');
  }
  if (isNum(summary.triangles_shown) && isNum(summary.triangles_machined) && summary.triangles_machined > summary.triangles_shown) {
    viewport.append(el('div', { class: 'decimated', text: `Showing ${num(summary.triangles_shown)} of ${num(summary.triangles_machined)} triangles` }));
  }
  if (!model.mesh) viewport.append(el('div', { class: 'view-error soft', text: 'No machined mesh in this report.' }));
  if (playbackError) viewport.append(el('div', { class: 'view-error soft', text: `No playback: its data is damaged (${playbackError}).` }));

  // Playback of the program: the machine, the tool and the part as cut, frame by frame.
  if (model.playback) {
    playback = new Playback(viewer, model.playback, partKeys, data.sources, events, (i) => {
      const row = document.querySelector(`#event-table tr[data-event-index="${i}"]`);
      if (row) row.scrollIntoView({ block: 'nearest' });
      if (eventActivators[i]) eventActivators[i]();
      else playback.showEvent(i);
    });
    viewport.classList.add('has-playback');
    viewport.append(playbackBar(model.playback, playback));
    window.vcutPlayback = {
      frames: () => model.playback.frames.count,
      frame: () => playback.index,
      setFrame: (i) => playback.setFrame(i),
      playing: () => playback.playing,
      frameOfEvent: (i) => playback.eventFrames[i],
      machineVisible: () => playback.root.visible,
      bodyNames: () => playback.bodyMeshes.map((m) => m.name),
      bodyBox: (name) => playback.bodyBox(name),
      partTriangles: () => playback.partTrianglesShown(),
      pathPoints: () => (playback.pathLine ? playback.pathLine.geometry.drawRange.count : 0),
      atEvent: () => playback.eventPose != null,
    };
  }

  window.vcutViewer = {
    cameraState: () => viewer.cameraState(),
    isAnimating: () => viewer.isAnimating(),
    flyTo: (p) => viewer.flyTo(p),
    setView: (name) => viewer.setView(name),
  };
  mark('scene');
  viewer.whenFirstFrame(() => {
    mark('first_frame');
    window.vcutReady = true;
  });
}

function start() {
  try {
    main();
  } catch (e) {
    console.error(e);
    fail('The report page failed', String(e && e.stack ? e.stack : e));
  }
}

// Paint a loading note first: parsing a 60 MB report takes a moment.
const app = document.getElementById('app');
if (app) app.append(el('div', { class: 'loading', text: 'Loading report…' }));
requestAnimationFrame(() => setTimeout(start, 0));
