// Deviation colour scale shared by the 3D view, the legend and the histogram.
// Within tolerance: near white. Gouge (d < 0): starts fading at the gouge tolerance, full red
// at 3x the gouge tolerance. Excess (d > 0): fades from the neutral band to full blue at the
// excess tolerance. No deviation (NaN): plain grey.

export const NEUTRAL = [0.87, 0.88, 0.89];
export const NO_DATA = [0.6, 0.62, 0.65];
export const GOUGE = [0.86, 0.08, 0.1];
export const EXCESS = [0.1, 0.32, 0.92];

export function makeScale(gougeTolMm, excessTolMm) {
  const g = gougeTolMm > 0 ? gougeTolMm : 0.02;
  const e = excessTolMm > 0 ? excessTolMm : 0.1;
  // Excess inside this band stays neutral: the cut surface carries a few hundredths of
  // resolution noise that is not worth colouring.
  const excessStart = Math.min(g, 0.5 * e);
  return { gouge: g, gougeFull: 3 * g, excess: e, excessStart };
}

const lerp = (a, b, t) => [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t];
// Smoothstep so the colour leaves the neutral band gently and saturates firmly.
const ease = (t) => t * t * (3 - 2 * t);

export function deviationColor(d, s) {
  if (!Number.isFinite(d)) return d === -Infinity ? GOUGE : d === Infinity ? EXCESS : NO_DATA;
  if (d < 0) {
    const t = (-d - s.gouge) / (s.gougeFull - s.gouge);
    return t <= 0 ? NEUTRAL : t >= 1 ? GOUGE : lerp(NEUTRAL, GOUGE, ease(t));
  }
  const t = (d - s.excessStart) / (s.excess - s.excessStart);
  return t <= 0 ? NEUTRAL : t >= 1 ? EXCESS : lerp(NEUTRAL, EXCESS, ease(t));
}

export function cssColor(c) {
  return `rgb(${Math.round(c[0] * 255)},${Math.round(c[1] * 255)},${Math.round(c[2] * 255)})`;
}

// Fills an RGB Uint8Array (normalized vertex colours) for the given deviations.
export function fillDeviationColors(out, deviation, s) {
  // A 256-entry lookup per side keeps a million-vertex mesh to a tight loop.
  const N = 256;
  const gl = new Uint8Array(N * 3);
  const el = new Uint8Array(N * 3);
  const gMax = s.gougeFull * 1.001;
  const eMax = s.excess * 1.001;
  for (let i = 0; i < N; i++) {
    const cg = deviationColor(-(i / (N - 1)) * gMax, s);
    const ce = deviationColor((i / (N - 1)) * eMax, s);
    for (let k = 0; k < 3; k++) {
      gl[i * 3 + k] = Math.round(cg[k] * 255);
      el[i * 3 + k] = Math.round(ce[k] * 255);
    }
  }
  const nd = NO_DATA.map((x) => Math.round(x * 255));
  const n = deviation.length;
  for (let i = 0; i < n; i++) {
    const d = deviation[i];
    const o = i * 3;
    if (d !== d) {
      out[o] = nd[0]; out[o + 1] = nd[1]; out[o + 2] = nd[2];
      continue;
    }
    let lut, j;
    if (d < 0) { lut = gl; j = Math.min(N - 1, Math.round((-d / gMax) * (N - 1))); }
    else { lut = el; j = Math.min(N - 1, Math.round((d / eMax) * (N - 1))); }
    out[o] = lut[j * 3]; out[o + 1] = lut[j * 3 + 1]; out[o + 2] = lut[j * 3 + 2];
  }
}
