// Small DOM and number-formatting helpers shared by the page modules.

export function el(tag, attrs, ...children) {
  const e = document.createElement(tag);
  if (attrs) {
    for (const [k, v] of Object.entries(attrs)) {
      if (v == null || v === false) continue;
      if (k === 'class') e.className = v;
      else if (k === 'text') e.textContent = v;
      else if (k === 'style') e.style.cssText = v;
      else if (k.startsWith('on')) e.addEventListener(k.slice(2), v);
      else e.setAttribute(k, v === true ? '' : String(v));
    }
  }
  for (const c of children.flat()) {
    if (c == null || c === false) continue;
    e.append(c instanceof Node ? c : document.createTextNode(String(c)));
  }
  return e;
}

const SVG_NS = 'http://www.w3.org/2000/svg';
export function svg(tag, attrs, ...children) {
  const e = document.createElementNS(SVG_NS, tag);
  if (attrs) {
    for (const [k, v] of Object.entries(attrs)) {
      if (v == null) continue;
      if (k === 'text') e.textContent = v;
      else e.setAttribute(k, String(v));
    }
  }
  for (const c of children.flat()) if (c) e.append(c);
  return e;
}

export const isNum = (v) => typeof v === 'number' && Number.isFinite(v);

// Fixed decimals, thin-space thousands grouping; '–' for missing values.
export function num(v, decimals = 0) {
  if (!isNum(v)) return '–';
  const s = v.toFixed(decimals);
  const [i, f] = s.split('.');
  const g = i.replace(/\B(?=(\d{3})+(?!\d))/g, '\u2009');
  return f != null ? `${g}.${f}` : g;
}

// Significant-figure formatting for values of unknown magnitude.
export function sig(v, digits = 3) {
  if (!isNum(v)) return '–';
  if (v === 0) return '0';
  const a = Math.abs(v);
  if (a >= 1e6 || a < 1e-3) return v.toExponential(digits - 1);
  const d = Math.max(0, digits - 1 - Math.floor(Math.log10(a)));
  return num(v, Math.min(d, 6));
}

export function mm(v, decimals = 3) {
  return isNum(v) ? `${num(v, decimals)} mm` : '–';
}

export function signedMm(v, decimals = 3) {
  if (!isNum(v)) return '–';
  const body = num(Math.abs(v), decimals);
  const zero = Number(Math.abs(v).toFixed(decimals)) === 0;
  return `${zero ? '' : v > 0 ? '+' : '−'}${body} mm`;
}

export function duration(s) {
  if (!isNum(s)) return '–';
  if (s < 60) return `${num(s, s < 10 ? 2 : 1)} s`;
  const h = Math.floor(s / 3600);
  const m = Math.floor((s % 3600) / 60);
  const sec = Math.round(s % 60);
  const pad = (x) => String(x).padStart(2, '0');
  return h > 0 ? `${h} h ${pad(m)} min ${pad(sec)} s` : `${m} min ${pad(sec)} s`;
}

export function volume(v) {
  if (!isNum(v)) return '–';
  if (Math.abs(v) >= 1e5) return `${num(v / 1000, 1)} cm³`;
  return `${num(v, v < 10 ? 3 : 1)} mm³`;
}

export function xyz(p, decimals = 3) {
  if (!Array.isArray(p) || p.length < 3) return '–';
  return p.map((c) => num(c, decimals)).join(', ');
}

// "finish.ngc:10180-10185" -> {file, from, to}; null when it does not parse.
export function parseLineRef(ref) {
  if (typeof ref !== 'string') return null;
  const m = /^(.*):(\d+)(?:-(\d+))?$/.exec(ref.trim());
  if (!m) return null;
  const from = Number(m[2]);
  return { file: m[1], from, to: m[3] != null ? Number(m[3]) : from };
}

export const basename = (p) => String(p).split(/[\\/]/).pop();
