// SVG charts: deviation histogram and time-series line charts (feed, contour error).
// Fixed viewBox, scaled to the container width; no external charting library.

import { svg, el, isNum, sig, num } from './format.js';
import { deviationColor, cssColor } from './colormap.js';

const W = 640;
const H = 250;
const M = { l: 62, r: 16, t: 14, b: 44 };

function niceStep(span, target) {
  const raw = span / Math.max(1, target);
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  const f = raw / p;
  return (f < 1.5 ? 1 : f < 3 ? 2 : f < 7 ? 5 : 10) * p;
}

function ticks(lo, hi, target = 5) {
  if (!(hi > lo)) return [lo];
  const step = niceStep(hi - lo, target);
  const out = [];
  for (let v = Math.ceil(lo / step - 1e-9) * step; v <= hi + step * 1e-9; v += step) out.push(Math.abs(v) < step * 1e-9 ? 0 : v);
  return out;
}

function tickLabel(v, step) {
  const d = Math.max(0, -Math.floor(Math.log10(step) + 1e-9));
  return num(v, Math.min(d, 6));
}

function frame(title, yLabel, xLabel) {
  const root = svg('svg', { viewBox: `0 0 ${W} ${H}`, class: 'chart', role: 'img', 'aria-label': title, preserveAspectRatio: 'xMidYMid meet' });
  root.append(svg('text', { x: 14, y: M.t + (H - M.t - M.b) / 2, class: 'axis-title', transform: `rotate(-90 14 ${M.t + (H - M.t - M.b) / 2})`, 'text-anchor': 'middle', text: yLabel }));
  root.append(svg('text', { x: M.l + (W - M.l - M.r) / 2, y: H - 6, class: 'axis-title', 'text-anchor': 'middle', text: xLabel }));
  return root;
}

function yAxis(root, lo, hi, sy, fmt) {
  const tv = ticks(lo, hi, 5);
  const step = tv.length > 1 ? tv[1] - tv[0] : 1;
  for (const v of tv) {
    const y = sy(v);
    root.append(svg('line', { x1: M.l, x2: W - M.r, y1: y, y2: y, class: 'grid' }));
    root.append(svg('text', { x: M.l - 6, y: y + 4, 'text-anchor': 'end', class: 'tick', text: fmt ? fmt(v) : tickLabel(v, step) }));
  }
}

export function emptyChart(msg) {
  return el('div', { class: 'chart-empty', text: msg });
}

// Histogram with bins given by edges (null at either end = open-ended bin). Bars are
// equal-width categories so open bins and uneven edges read cleanly.
export function histogramChart(hist, scale) {
  const edges = hist.edges_mm || [];
  const counts = hist.counts || [];
  const areas = Array.isArray(hist.area_mm2) && hist.area_mm2.length === counts.length ? hist.area_mm2 : null;
  const n = Math.min(counts.length, Math.max(0, edges.length - 1));
  if (n === 0) return emptyChart('No histogram data.');
  const wrap = el('div', { class: 'chart-wrap' });
  const controls = el('div', { class: 'chart-controls' });
  let useArea = !!areas;
  let log = true;
  const draw = () => {
    const values = [];
    for (let i = 0; i < n; i++) values.push(useArea ? Number(areas[i]) || 0 : Number(counts[i]) || 0);
    const root = frame('Deviation histogram', useArea ? 'area (mm²)' : 'vertices', 'deviation (mm): gouge < 0 < excess');
    const maxV = Math.max(...values, 0);
    const pw = W - M.l - M.r;
    const ph = H - M.t - M.b;
    const positive = values.filter((v) => v > 0);
    const minPos = positive.length ? Math.min(...positive) : 1;
    const logLo = Math.floor(Math.log10(minPos));
    const logHi = Math.max(logLo + 1, Math.ceil(Math.log10(Math.max(maxV, 1e-12))));
    const sy = log
      ? (v) => (v <= 0 ? M.t + ph : M.t + ph - ((Math.log10(v) - logLo) / (logHi - logLo)) * ph)
      : (v) => M.t + ph - (maxV > 0 ? (v / maxV) * ph : 0);
    if (log) {
      for (let e = logLo; e <= logHi; e++) {
        const y = sy(Math.pow(10, e));
        root.append(svg('line', { x1: M.l, x2: W - M.r, y1: y, y2: y, class: 'grid' }));
        root.append(svg('text', { x: M.l - 6, y: y + 4, 'text-anchor': 'end', class: 'tick', text: e >= -2 && e <= 5 ? num(Math.pow(10, e), Math.max(0, -e)) : `1e${e}` }));
      }
    } else {
      yAxis(root, 0, maxV || 1, sy, (v) => sig(v, 3));
    }
    const bw = pw / n;
    const labelEvery = Math.ceil(n / 12);
    for (let i = 0; i < n; i++) {
      const lo = edges[i];
      const hi = edges[i + 1];
      let c;
      if (!isNum(lo)) c = deviationColor(isNum(hi) ? Math.min(hi, 0) - 1e3 : -1e3, scale);
      else if (!isNum(hi)) c = deviationColor(Math.max(lo, 0) + 1e3, scale);
      else c = deviationColor((lo + hi) / 2, scale);
      const v = values[i];
      const y = sy(v);
      const x = M.l + i * bw;
      const label = `${isNum(lo) ? sig(lo, 3) : '−∞'} … ${isNum(hi) ? sig(hi, 3) : '+∞'} mm`;
      const tip = `${label}\n${num(Number(counts[i]) || 0)} vertices${areas ? `\n${sig(Number(areas[i]) || 0, 4)} mm²` : ''}`;
      const bar = svg('rect', {
        x: x + 0.5, y, width: Math.max(0.5, bw - 1), height: Math.max(0, M.t + ph - y),
        fill: cssColor(c), class: 'bar',
      });
      bar.append(svg('title', { text: tip }));
      root.append(bar);
      if (i % labelEvery === 0 || i === n) {
        const ex = M.l + i * bw;
        root.append(svg('text', { x: ex, y: M.t + ph + 16, 'text-anchor': 'middle', class: 'tick', text: isNum(lo) ? sig(lo, 2) : '−∞' }));
      }
    }
    root.append(svg('text', { x: W - M.r, y: M.t + ph + 16, 'text-anchor': 'middle', class: 'tick', text: isNum(edges[n]) ? sig(edges[n], 2) : '+∞' }));
    root.append(svg('line', { x1: M.l, x2: W - M.r, y1: M.t + ph, y2: M.t + ph, class: 'axis' }));
    wrap.replaceChildren(controls, root);
  };
  const toggle = (label, get, set) => {
    const b = el('button', { class: 'chip', type: 'button', text: label });
    const sync = () => b.classList.toggle('on', get());
    b.addEventListener('click', () => { set(!get()); sync(); draw(); });
    sync();
    return b;
  };
  controls.append(toggle('log scale', () => log, (v) => { log = v; }));
  if (areas) controls.append(toggle('by area', () => useArea, (v) => { useArea = v; }));
  draw();
  return wrap;
}

// Reduces a series to at most ~2 points per horizontal pixel (min and max of each column),
// so a 200 000-sample timeline draws as a few thousand SVG vertices.
function decimate(xs, ys, x0, x1, columns) {
  const n = Math.min(xs.length, ys.length);
  if (n <= columns * 2) {
    const out = [];
    for (let i = 0; i < n; i++) if (isNum(xs[i]) && isNum(ys[i])) out.push([xs[i], ys[i]]);
    return out;
  }
  const out = [];
  let col = -1;
  let lo = null;
  let hi = null;
  const flush = () => {
    if (!lo) return;
    if (lo[0] <= hi[0]) out.push(lo, hi); else out.push(hi, lo);
  };
  for (let i = 0; i < n; i++) {
    const x = xs[i];
    const y = ys[i];
    if (!isNum(x) || !isNum(y)) continue;
    const c = Math.floor(((x - x0) / (x1 - x0 || 1)) * columns);
    if (c !== col) { flush(); col = c; lo = hi = [x, y]; }
    else { if (y < lo[1]) lo = [x, y]; if (y > hi[1]) hi = [x, y]; }
  }
  flush();
  return out;
}

export function lineChart({ xs, ys, title, yLabel, xLabel, color, unit, decimals = 0 }) {
  const n = Math.min(xs ? xs.length : 0, ys ? ys.length : 0);
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (let i = 0; i < n; i++) {
    if (!isNum(xs[i]) || !isNum(ys[i])) continue;
    x0 = Math.min(x0, xs[i]); x1 = Math.max(x1, xs[i]);
    y0 = Math.min(y0, ys[i]); y1 = Math.max(y1, ys[i]);
  }
  if (!(x1 >= x0) || !(y1 >= y0)) return emptyChart(`No ${title.toLowerCase()} data.`);
  if (x1 === x0) x1 = x0 + 1;
  y0 = Math.min(0, y0);
  if (y1 === y0) y1 = y0 + 1;
  const ySpan = y1 - y0;
  y1 += ySpan * 0.06;
  const pw = W - M.l - M.r;
  const ph = H - M.t - M.b;
  const sx = (x) => M.l + ((x - x0) / (x1 - x0)) * pw;
  const sy = (y) => M.t + ph - ((y - y0) / (y1 - y0)) * ph;
  const root = frame(title, yLabel, xLabel);
  yAxis(root, y0, y1, sy);
  const xt = ticks(x0, x1, 7);
  const xstep = xt.length > 1 ? xt[1] - xt[0] : 1;
  for (const v of xt) {
    root.append(svg('line', { x1: sx(v), x2: sx(v), y1: M.t + ph, y2: M.t + ph + 4, class: 'axis' }));
    root.append(svg('text', { x: sx(v), y: M.t + ph + 16, 'text-anchor': 'middle', class: 'tick', text: tickLabel(v, xstep) }));
  }
  root.append(svg('line', { x1: M.l, x2: W - M.r, y1: M.t + ph, y2: M.t + ph, class: 'axis' }));
  const pts = decimate(xs, ys, x0, x1, pw * 2);
  let d = '';
  for (let i = 0; i < pts.length; i++) d += `${i ? 'L' : 'M'}${sx(pts[i][0]).toFixed(1)},${sy(pts[i][1]).toFixed(1)}`;
  root.append(svg('path', { d: `${d}L${sx(pts[pts.length - 1][0]).toFixed(1)},${sy(y0).toFixed(1)}L${sx(pts[0][0]).toFixed(1)},${sy(y0).toFixed(1)}Z`, fill: color, 'fill-opacity': 0.12, stroke: 'none' }));
  root.append(svg('path', { d, fill: 'none', stroke: color, 'stroke-width': 1.3, 'stroke-linejoin': 'round', class: 'series' }));

  // Hover readout: nearest sample by time.
  const cursor = svg('line', { y1: M.t, y2: M.t + ph, class: 'cursor', visibility: 'hidden' });
  const dot = svg('circle', { r: 3.5, fill: color, visibility: 'hidden' });
  const readout = svg('text', { x: W - M.r, y: M.t + 12, 'text-anchor': 'end', class: 'readout' });
  root.append(cursor, dot, readout);
  const hit = svg('rect', { x: M.l, y: M.t, width: pw, height: ph, fill: 'transparent' });
  root.append(hit);
  const order = [];
  for (let i = 0; i < n; i++) if (isNum(xs[i]) && isNum(ys[i])) order.push(i);
  hit.addEventListener('mousemove', (e) => {
    const r = root.getBoundingClientRect();
    const vx = ((e.clientX - r.left) / r.width) * W;
    const x = x0 + ((vx - M.l) / pw) * (x1 - x0);
    let lo = 0, hi = order.length - 1;
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (xs[order[mid]] < x) lo = mid; else hi = mid; }
    const i = Math.abs(xs[order[lo]] - x) <= Math.abs(xs[order[hi]] - x) ? order[lo] : order[hi];
    cursor.setAttribute('x1', sx(xs[i])); cursor.setAttribute('x2', sx(xs[i]));
    dot.setAttribute('cx', sx(xs[i])); dot.setAttribute('cy', sy(ys[i]));
    cursor.setAttribute('visibility', 'visible'); dot.setAttribute('visibility', 'visible');
    readout.textContent = `t = ${num(xs[i], 2)} s   ${num(ys[i], decimals)} ${unit}`;
  });
  hit.addEventListener('mouseleave', () => {
    cursor.setAttribute('visibility', 'hidden'); dot.setAttribute('visibility', 'hidden');
    readout.textContent = '';
  });
  return root;
}
