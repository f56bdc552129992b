// The program played back on the page (issue #25): the machine's bodies, the fixtures and the
// tool posed frame by frame (vcut computes the poses: pipeline::Playback), the programmed tool
// path coloured by rapid and feed and drawn up to the frame, and the part as cut up to the
// frame's block (its triangles ordered by the block that made them, drawn up to that block).
// Frame: the part's (workpiece) frame, as the rest of the view, the machine moving around the
// part; or the machine's frame (the toggle), the part moving with its table.

import {
  BufferGeometry, BufferAttribute, Group, Line, LineBasicMaterial, Matrix4, Mesh, MeshStandardMaterial, DoubleSide, Box3,
} from 'three';
import { decodeMesh, typed } from './decode.js';
import { el, num, basename } from './format.js';

const BODY_STYLE = {
  model: { color: 0x8da2b8, opacity: 0.38 },
  fixture: { color: 0xb07a3c, opacity: 0.75 },
  cutter: { color: 0xe8c040, opacity: 1 },
  shank: { color: 0xa8b0b8, opacity: 1 },
  holder: { color: 0x505a66, opacity: 1 },
};
const RAPID_RGB = [1.0, 0.42, 0.2];
const FEED_RGB = [0.25, 0.8, 1.0];
const SPEEDS = [1, 5, 25, 100, 500];
const FALLBACK_FPS = 30; // frames per second of playback when the report has no time stamps

// ---- data ---------------------------------------------------------------------------------

// Decodes the report's `playback` (web/README.md); null when there is none.
export function decodePlayback(p) {
  if (!p || !p.frames || !(Number(p.frames.count) > 0)) return null;
  const nodes = Array.isArray(p.nodes) ? p.nodes.map(String) : [];
  const n = Number(p.frames.count);
  const per = 12 * (nodes.length + 1); // floats of a whole pose (an event's)
  // Each pose of a frame: 12 floats, or 3 (the translation) where its rotation never changes.
  const layout = (p.frames.layout || []).map((l) => ({ rotation: Array.isArray(l.rotation) ? l.rotation.map(Number) : null }));
  if (layout.length !== nodes.length + 1) throw new Error(`playback.frames.layout: expected ${nodes.length + 1} entries`);
  let perFrame = 0;
  for (const l of layout) {
    l.offset = perFrame;
    perFrame += l.rotation ? 3 : 12;
  }
  const bodies = (p.bodies || []).map((b, i) => {
    const node = Number(b.node);
    if (!(node >= 0 && node < nodes.length)) throw new Error(`playback.bodies[${i}]: node ${b.node} out of range`);
    return { name: String(b.name), kind: String(b.kind), node, tool: Number(b.tool) || 0, mesh: decodeMesh(b.mesh, `playback.bodies[${i}].mesh`) };
  });
  const f = p.frames;
  const frames = {
    count: n,
    t: typed(f.t_s, Float32Array, n, 'playback.frames.t_s'),
    sample: typed(f.sample, Int32Array, n, 'playback.frames.sample'),
    block: typed(f.block, Int32Array, n, 'playback.frames.block'),
    tool: typed(f.tool, Int32Array, n, 'playback.frames.tool'),
    source: typed(f.source, Int32Array, n, 'playback.frames.source'),
    pose: typed(f.pose, Float32Array, n * perFrame, 'playback.frames.pose'),
    layout,
    perFrame,
  };
  const m = Number(p.path && p.path.points) || 0;
  const path = m > 0 ? {
    points: m,
    position: typed(p.path.position, Float32Array, 3 * m, 'playback.path.position'),
    block: typed(p.path.block, Int32Array, m, 'playback.path.block'),
    rapid: typed(p.path.rapid, Uint8Array, m, 'playback.path.rapid'),
  } : null;
  // Times must rise for the search by time; without a timeline (all zero) frames play at a fixed rate.
  let timed = frames.t[n - 1] > 0;
  for (let i = 1; i < n && timed; i++) if (!(frames.t[i] >= frames.t[i - 1])) timed = false;
  if (!timed) for (let i = 0; i < n; i++) frames.t[i] = i / FALLBACK_FPS;
  return { nodes, per, bodies, frames, path, timed };
}

// Reorders the part's triangles by the block that made them (a triangle: the latest of its
// vertices' blocks; -1, the initial stock, first) and returns the sorted keys, so that the
// part as cut up to block b is the first (number of keys <= b) triangles. Stable: equal keys
// keep their order.
export function orderTrianglesByBlock(mesh) {
  if (!mesh || !mesh.block) return null;
  const idx = mesh.indices;
  const nt = idx.length / 3;
  const key = new Int32Array(nt);
  let max = -1;
  for (let t = 0; t < nt; t++) {
    const k = Math.max(mesh.block[idx[3 * t]], mesh.block[idx[3 * t + 1]], mesh.block[idx[3 * t + 2]]);
    key[t] = k;
    if (k > max) max = k;
  }
  // Counting sort over -1 .. max.
  const counts = new Uint32Array(max + 3);
  for (let t = 0; t < nt; t++) counts[key[t] + 2]++;
  for (let k = 1; k < counts.length; k++) counts[k] += counts[k - 1];
  const sortedIdx = new Uint32Array(idx.length);
  const sortedKey = new Int32Array(nt);
  for (let t = 0; t < nt; t++) {
    const at = counts[key[t] + 1]++;
    sortedKey[at] = key[t];
    sortedIdx[3 * at] = idx[3 * t];
    sortedIdx[3 * at + 1] = idx[3 * t + 1];
    sortedIdx[3 * at + 2] = idx[3 * t + 2];
  }
  idx.set(sortedIdx);
  return sortedKey;
}

// First index in a rising array whose value exceeds x.
function upperBound(arr, x, n = arr.length) {
  let lo = 0;
  let hi = n;
  while (lo < hi) {
    const mid = (lo + hi) >> 1;
    if (arr[mid] <= x) lo = mid + 1;
    else hi = mid;
  }
  return lo;
}

// A 3 x 4 pose [R | t], row by row, from 12 floats; or R given and t from 3 floats.
function matrixFrom(m, floats, at, rotation = null) {
  const f = floats;
  if (rotation) {
    const r = rotation;
    return m.set(r[0], r[1], r[2], f[at], r[3], r[4], r[5], f[at + 1], r[6], r[7], r[8], f[at + 2], 0, 0, 0, 1);
  }
  return m.set(
    f[at], f[at + 1], f[at + 2], f[at + 3],
    f[at + 4], f[at + 5], f[at + 6], f[at + 7],
    f[at + 8], f[at + 9], f[at + 10], f[at + 11],
    0, 0, 0, 1);
}

// ---- the view and its controls ------------------------------------------------------------

export class Playback {
  // viewer: the Viewer (its scene, part and requestRender). pb: decodePlayback's result.
  // partKeys: orderTrianglesByBlock's result (null: the part is shown whole). sources: the
  // report's sources table. events: the report's events. onEvent(i): a jump to event i
  // (the page selects its row and shows its lines).
  constructor(viewer, pb, partKeys, sources, events, onEvent) {
    this.viewer = viewer;
    this.pb = pb;
    this.partKeys = partKeys;
    this.sources = sources || [];
    this.events = events || [];
    this.onEvent = onEvent;
    this.index = pb.frames.count - 1;
    this.playing = false;
    this.speed = SPEEDS[1];
    this.clock = pb.frames.t[this.index];
    this.eventPose = null; // an event's exact instant, shown until the frame changes

    this.root = new Group();
    this.root.visible = false;
    this.nodeGroups = pb.nodes.map(() => {
      const g = new Group();
      g.matrixAutoUpdate = false;
      this.root.add(g);
      return g;
    });
    this.bodyMeshes = pb.bodies.map((b) => {
      const g = new BufferGeometry();
      g.setAttribute('position', new BufferAttribute(b.mesh.positions, 3));
      g.setIndex(new BufferAttribute(b.mesh.indices, 1));
      g.computeVertexNormals();
      const style = BODY_STYLE[b.kind] || BODY_STYLE.model;
      const mat = new MeshStandardMaterial({
        color: style.color, metalness: 0.2, roughness: 0.6, flatShading: true, side: DoubleSide,
        transparent: style.opacity < 1, opacity: style.opacity, depthWrite: style.opacity >= 1,
      });
      const mesh = new Mesh(g, mat);
      mesh.name = b.name;
      mesh.renderOrder = style.opacity < 1 ? 4 : 1;
      mesh.userData.tool = b.tool;
      this.nodeGroups[b.node].add(mesh);
      return mesh;
    });
    viewer.world.add(this.root);
    this.machineFrame = false;
    this.buildPath();
    this.eventFrames = this.events.map((e) => this.frameOfEvent(e));
    this.apply();
  }

  buildPath() {
    this.pathLine = null;
    const p = this.pb.path;
    if (!p) return;
    const colors = new Float32Array(p.points * 3);
    for (let i = 0; i < p.points; i++) colors.set(p.rapid[i] ? RAPID_RGB : FEED_RGB, 3 * i);
    const g = new BufferGeometry();
    g.setAttribute('position', new BufferAttribute(p.position, 3));
    g.setAttribute('color', new BufferAttribute(colors, 3));
    g.computeBoundingSphere();
    this.pathLine = new Line(g, new LineBasicMaterial({ vertexColors: true, transparent: true, opacity: 0.9 }));
    this.pathLine.renderOrder = 5;
    this.pathLine.visible = false;
    this.viewer.world.add(this.pathLine);
  }

  // The frame of an event: the one at (or before) its pose, else the first of its block.
  frameOfEvent(e) {
    const f = this.pb.frames;
    if (Number.isInteger(e.sample)) return Math.max(0, upperBound(f.sample, e.sample) - 1);
    if (Number.isInteger(e.block) && e.block >= 0) {
      for (let i = 0; i < f.count; i++) if (f.block[i] >= e.block) return i;
    }
    return null;
  }

  // ---- state ----------------------------------------------------------------------------

  setMachineVisible(on) {
    this.root.visible = on;
    this.viewer.requestRender();
    if (this.onState) this.onState();
  }

  // The view in the machine's frame (the workpiece frame where the frame's last pose puts it),
  // or in the workpiece frame. The camera keeps what it looks at.
  setMachineFrame(on) {
    this.machineFrame = on;
    this.viewer.setWorldMatrix(on ? this.workpieceMatrix() : new Matrix4(), true);
    if (this.onState) this.onState();
  }

  workpieceMatrix() {
    const f = this.pb.frames;
    const k = this.nodeGroups.length;
    if (this.eventPose) return matrixFrom(new Matrix4(), this.eventPose, 12 * k);
    return matrixFrom(new Matrix4(), f.pose, this.index * f.perFrame + f.layout[k].offset, f.layout[k].rotation);
  }

  setPathVisible(on) {
    if (this.pathLine) this.pathLine.visible = on;
    this.viewer.requestRender();
    if (this.onState) this.onState();
  }

  // Shows frame i (the machine, the tool in the spindle, the path and the part up to it).
  setFrame(i, keepClock = false) {
    const n = this.pb.frames.count;
    this.index = Math.max(0, Math.min(n - 1, Math.round(i)));
    if (!keepClock) this.clock = this.pb.frames.t[this.index];
    this.eventPose = null;
    this.apply();
  }

  // Event i: its frame, and where it carries the machine's pose at its instant, that pose.
  showEvent(i) {
    const frame = this.eventFrames[i];
    if (frame == null) return false;
    this.pause();
    this.setFrame(frame);
    const pose = this.events[i].pose;
    if (Array.isArray(pose) && pose.length === this.pb.per) {
      this.eventPose = Float32Array.from(pose);
      this.apply();
    }
    if (!this.root.visible && this.onActivate) this.onActivate();
    return true;
  }

  nextEvent() {
    let best = -1;
    for (let k = 0; k < this.eventFrames.length; k++) {
      const f = this.eventFrames[k];
      if (f == null || f <= this.index) continue;
      if (best < 0 || f < this.eventFrames[best]) best = k;
    }
    if (best < 0) return -1;
    if (this.onEvent) this.onEvent(best);
    else this.showEvent(best);
    return best;
  }

  apply() {
    const f = this.pb.frames;
    const i = this.index;
    this.nodeGroups.forEach((g, k) => {
      if (this.eventPose) matrixFrom(g.matrix, this.eventPose, 12 * k);
      else matrixFrom(g.matrix, f.pose, i * f.perFrame + f.layout[k].offset, f.layout[k].rotation);
      g.matrixWorldNeedsUpdate = true;
    });
    if (this.machineFrame) this.viewer.setWorldMatrix(this.workpieceMatrix());
    const tool = f.tool[i];
    for (const m of this.bodyMeshes) m.visible = m.userData.tool === 0 || m.userData.tool === tool;
    const block = f.block[i];
    if (this.pathLine) {
      const shown = i === f.count - 1 ? this.pb.path.points : upperBound(this.pb.path.block, block);
      this.pathLine.geometry.setDrawRange(0, shown);
    }
    const part = this.viewer.part;
    if (part && this.partKeys) {
      const count = i === f.count - 1 ? this.partKeys.length : upperBound(this.partKeys, block);
      part.geometry.setDrawRange(0, 3 * count);
    }
    this.viewer.requestRender();
    if (this.onFrame) this.onFrame();
  }

  // ---- time -----------------------------------------------------------------------------

  play() {
    if (this.playing) return;
    const f = this.pb.frames;
    if (this.index >= f.count - 1) this.setFrame(0);
    this.playing = true;
    let last = performance.now();
    const step = (now) => {
      if (!this.playing) return;
      this.clock += ((now - last) / 1000) * this.speed;
      last = now;
      const next = Math.max(0, upperBound(f.t, this.clock) - 1);
      if (next !== this.index) this.setFrame(next, true);
      if (this.index >= f.count - 1) { this.pause(); return; }
      requestAnimationFrame(step);
    };
    requestAnimationFrame(step);
    if (this.onState) this.onState();
  }

  pause() {
    if (!this.playing) return;
    this.playing = false;
    if (this.onState) this.onState();
  }

  // ---- for tests --------------------------------------------------------------------------

  // The axis-aligned box of a body's mesh as posed now, in the view's frame (the workpiece
  // frame unless the machine's frame is on).
  bodyBox(name) {
    const m = this.bodyMeshes.find((b) => b.name === name);
    if (!m) return null;
    this.viewer.world.updateMatrixWorld(true); // now, not at the next render
    const box = new Box3().setFromObject(m, true);
    return { min: box.min.toArray(), max: box.max.toArray(), visible: m.visible && this.root.visible };
  }

  partTrianglesShown() {
    const part = this.viewer.part;
    if (!part) return 0;
    const r = part.geometry.drawRange;
    const total = part.geometry.index.count;
    return Math.min(total, r.count) / 3;
  }
}

// The bar under the view: play/pause, the frame slider, the speed, the next event, the
// machine and tool path toggles, and where the frame is (time, NC line).
export function playbackBar(pb, playback) {
  const f = pb.frames;
  const playBtn = el('button', { type: 'button', class: 'tool', id: 'playback-play', title: 'Play / pause', text: 'Play' });
  const slider = el('input', {
    type: 'range', id: 'playback-slider', min: 0, max: f.count - 1, step: 1, value: playback.index,
    'aria-label': 'Frame of the program',
  });
  const speed = el('select', { id: 'playback-speed', class: 'speed', title: 'Playback speed' },
    SPEEDS.map((s) => el('option', { value: s, text: `${s}×`, selected: s === playback.speed })));
  const nextBtn = el('button', { type: 'button', class: 'tool', id: 'playback-next-event', title: 'Jump to the next event', text: 'Next event' });
  const machineBtn = el('button', { type: 'button', class: 'tool', id: 'toggle-machine', 'aria-pressed': 'false', text: 'Machine' });
  const frameBtn = el('button', {
    type: 'button', class: 'tool', id: 'toggle-machine-frame', 'aria-pressed': 'false', text: 'Machine frame',
    title: 'Hold the machine still and move the part with its table (else the part stays still)',
  });
  const pathBtn = el('button', { type: 'button', class: 'tool', id: 'toggle-path', 'aria-pressed': 'false', text: 'Tool path', disabled: !playback.pathLine });
  const readout = el('div', { class: 'playback-readout', id: 'playback-readout' });

  const activate = () => {
    if (!playback.root.visible) playback.setMachineVisible(true);
  };
  playback.onActivate = activate;
  playback.onState = () => {
    playBtn.textContent = playback.playing ? 'Pause' : 'Play';
    playBtn.classList.toggle('on', playback.playing);
    machineBtn.classList.toggle('on', playback.root.visible);
    machineBtn.setAttribute('aria-pressed', String(playback.root.visible));
    frameBtn.classList.toggle('on', playback.machineFrame);
    frameBtn.setAttribute('aria-pressed', String(playback.machineFrame));
    const pathOn = !!(playback.pathLine && playback.pathLine.visible);
    pathBtn.classList.toggle('on', pathOn);
    pathBtn.setAttribute('aria-pressed', String(pathOn));
  };
  const total = f.t[f.count - 1];
  playback.onFrame = () => {
    const i = playback.index;
    slider.value = String(i);
    const src = f.source[i] >= 0 ? playback.sources[f.source[i]] : null;
    const time = pb.timed ? `${num(f.t[i], 1)} s of ${num(total, 1)} s` : `frame ${i + 1} of ${f.count}`;
    const line = src ? `${basename(src.file)}:${src.line}` : 'start';
    readout.replaceChildren(...[
      el('span', { class: 'pb-time', text: time }),
      el('span', { class: 'pb-line', text: line, title: src ? `${src.file}:${src.line}` : '' }),
      src && src.text ? el('code', { class: 'pb-text', text: src.text }) : null,
      playback.eventPose ? el('span', { class: 'pb-event', text: 'at the event\'s instant' }) : null].filter(Boolean));
  };
  playBtn.addEventListener('click', () => {
    activate();
    if (playback.playing) playback.pause();
    else playback.play();
  });
  slider.addEventListener('input', () => {
    activate();
    playback.pause();
    playback.setFrame(Number(slider.value));
  });
  speed.addEventListener('change', () => { playback.speed = Number(speed.value); });
  nextBtn.addEventListener('click', () => {
    activate();
    playback.nextEvent();
  });
  machineBtn.addEventListener('click', () => playback.setMachineVisible(!playback.root.visible));
  frameBtn.addEventListener('click', () => playback.setMachineFrame(!playback.machineFrame));
  pathBtn.addEventListener('click', () => playback.setPathVisible(!playback.pathLine.visible));
  nextBtn.disabled = !playback.eventFrames.some((x) => x != null);
  // Keys, where no control has the focus: Space plays or pauses, the arrows step a frame.
  window.addEventListener('keydown', (e) => {
    const t = e.target;
    if (e.ctrlKey || e.metaKey || e.altKey || (t && /^(INPUT|SELECT|TEXTAREA|BUTTON)$/.test(t.tagName))) return;
    if (t && t.closest && t.closest('#event-table, #gouge-table, #excess-table')) return; // rows take Space and Enter
    if (e.key === ' ') {
      e.preventDefault();
      playBtn.click();
    } else if (e.key === 'ArrowRight' || e.key === 'ArrowLeft') {
      e.preventDefault();
      activate();
      playback.pause();
      playback.setFrame(playback.index + (e.key === 'ArrowRight' ? 1 : -1));
    }
  });
  playback.onState();
  playback.onFrame();
  return el('div', { class: 'playback-bar', id: 'playback-bar' },
    el('div', { class: 'tool-group' }, playBtn, speed),
    slider,
    el('div', { class: 'tool-group' }, nextBtn, machineBtn, frameBtn, pathBtn),
    readout);
}
