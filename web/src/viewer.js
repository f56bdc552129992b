// The 3D view: machined part coloured by deviation, design overlay, initial stock, markers.
// Frame: the part's (workpiece) frame as vcut writes it, z up, millimetres.
// Renders on demand (orbit, animation, toggles) so an idle page costs no CPU.

import {
  WebGLRenderer, Scene, PerspectiveCamera, OrthographicCamera, Color, BufferGeometry,
  BufferAttribute, Float32BufferAttribute, Mesh, MeshStandardMaterial, MeshBasicMaterial,
  HemisphereLight, DirectionalLight, Vector3, Vector2, Raycaster, Box3, Sphere, LineSegments,
  LineBasicMaterial, EdgesGeometry, BoxGeometry, SphereGeometry, Group, DoubleSide, Points,
  PointsMaterial, CanvasTexture, SRGBColorSpace,
} from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';
import { fillDeviationColors, makeScale, NO_DATA } from './colormap.js';
import { el } from './format.js';

const BACKGROUND = 0x2a323c;
const PLAIN_COLOR = 0xc4c9cf;
const DESIGN_COLOR = 0x3fbf7f;
const STOCK_COLOR = 0xf0a040;
const MARKER_COLOR = 0xffc400;
const FLY_MS = 600;
const CLICK_SLOP_PX = 5;

const VIEW_DIRS = {
  iso: [-0.55, -1.35, 1.05],
  top: [0, -1e-4, 1],
  front: [0, -1, 0],
  right: [1, 0, 0],
  left: [-1, 0, 0],
  back: [0, 1, 0],
};

const easeInOutCubic = (t) => (t < 0.5 ? 4 * t * t * t : 1 - Math.pow(-2 * t + 2, 3) / 2);

function geometryFrom(m, withNormals = true) {
  const g = new BufferGeometry();
  g.setAttribute('position', new BufferAttribute(m.positions, 3));
  g.setIndex(new BufferAttribute(m.indices, 1));
  if (withNormals) g.computeVertexNormals();
  g.computeBoundingBox();
  g.computeBoundingSphere();
  return g;
}

function roundSpriteTexture() {
  const c = document.createElement('canvas');
  c.width = c.height = 64;
  const ctx = c.getContext('2d');
  ctx.beginPath();
  ctx.arc(32, 32, 26, 0, Math.PI * 2);
  ctx.fillStyle = '#fff';
  ctx.fill();
  ctx.lineWidth = 7;
  ctx.strokeStyle = 'rgba(20,20,20,0.85)';
  ctx.stroke();
  const t = new CanvasTexture(c);
  t.colorSpace = SRGBColorSpace;
  return t;
}

export class Viewer {
  // container: element the canvas fills. data: the decoded report ({mesh, design, stock,
  // tolerances}). onPick(info|null) is called for clicks on the part.
  constructor(container, model, onPick) {
    this.container = container;
    this.model = model;
    this.onPick = onPick;
    this.anim = null;
    this.frameRequested = false;
    this.firstFrameDone = false;
    this.readyCallbacks = [];

    // Throws when no WebGL context can be created; the caller shows the message.
    const renderer = new WebGLRenderer({ antialias: true, powerPreference: 'high-performance' });
    renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, 2));
    renderer.setClearColor(BACKGROUND, 1);
    renderer.domElement.className = 'view-canvas';
    renderer.domElement.addEventListener('webglcontextlost', (e) => {
      e.preventDefault();
      this.showOverlayError('The WebGL context was lost (GPU reset or out of memory). Reload the page.');
    });
    container.append(renderer.domElement);
    this.renderer = renderer;

    const scene = new Scene();
    this.scene = scene;
    const camera = new PerspectiveCamera(35, 1, 0.1, 1000);
    camera.up.set(0, 0, 1);
    this.camera = camera;

    scene.add(new HemisphereLight(0xffffff, 0x50555c, 1.4));
    const key = new DirectionalLight(0xffffff, 1.6);
    key.position.set(-0.4, 0.6, 1); // relative to the camera: upper left of the view
    camera.add(key);
    camera.add(key.target);
    const fill = new DirectionalLight(0xffffff, 0.5);
    fill.position.set(1, -1, 2);
    scene.add(fill);
    scene.add(camera);
    // What the report places in the workpiece frame; the playback can set where that frame
    // stands (the machine's frame fixed, the part moving with its table).
    this.world = new Group();
    this.world.matrixAutoUpdate = false;
    scene.add(this.world);

    this.buildPart();
    this.buildDesign();
    this.buildStock();
    this.buildMarker();
    this.buildRegionMarkers();
    this.buildTriad();

    const bounds = new Box3();
    for (const o of [this.part, this.design, this.stock]) {
      if (o) bounds.expandByObject(o);
    }
    if (bounds.isEmpty()) bounds.set(new Vector3(-1, -1, -1), new Vector3(1, 1, 1));
    this.sceneRadius = Math.max(bounds.getBoundingSphere(new Sphere()).radius, 1e-3);
    // Views frame the machined part; the hidden stock and design only matter for clipping.
    this.bounds = this.part ? this.part.geometry.boundingBox.clone() : bounds;
    this.radius = Math.max(this.bounds.getBoundingSphere(new Sphere()).radius, 1e-3);

    const controls = new OrbitControls(camera, renderer.domElement);
    controls.enableDamping = false; // CAD-like: the view stops where the mouse stops
    controls.zoomToCursor = true;
    controls.screenSpacePanning = true;
    controls.rotateSpeed = 0.9;
    controls.addEventListener('change', () => this.requestRender());
    controls.addEventListener('start', () => this.cancelAnimation());
    this.controls = controls;

    this.setView('iso', false);
    this.installPicking();

    this.resizeObserver = new ResizeObserver(() => this.resize());
    this.resizeObserver.observe(container);
    this.resize();
  }

  // ---- scene content ------------------------------------------------------------------

  buildPart() {
    const m = this.model.mesh;
    this.part = null;
    this.hasDeviation = false;
    if (!m || m.triangles === 0) return;
    const g = geometryFrom(m);
    let finite = 0;
    if (m.deviation) {
      for (let i = 0; i < m.deviation.length; i++) if (m.deviation[i] === m.deviation[i]) { finite++; break; }
    }
    this.hasDeviation = finite > 0;
    if (this.hasDeviation) {
      const colors = new Uint8Array(m.vertices * 3);
      fillDeviationColors(colors, m.deviation, makeScale(this.model.gougeTol, this.model.excessTol));
      g.setAttribute('color', new BufferAttribute(colors, 3, true));
    }
    const mat = new MeshStandardMaterial({
      color: this.hasDeviation ? 0xffffff : PLAIN_COLOR,
      vertexColors: this.hasDeviation,
      metalness: 0.15,
      roughness: 0.55,
      side: DoubleSide,
      polygonOffset: true, // lets the design overlay sit exactly on the part without z-fighting
      polygonOffsetFactor: 1,
      polygonOffsetUnits: 1,
    });
    this.part = new Mesh(g, mat);
    this.part.renderOrder = 0;
    this.world.add(this.part);
    this.colorByDeviation = this.hasDeviation;
  }

  buildDesign() {
    this.design = null;
    const d = this.model.design;
    if (!d || d.triangles === 0) return;
    const g = geometryFrom(d);
    const mat = new MeshStandardMaterial({
      color: DESIGN_COLOR, transparent: true, opacity: 0.3, depthWrite: false,
      side: DoubleSide, metalness: 0, roughness: 0.8,
    });
    this.design = new Mesh(g, mat);
    this.design.renderOrder = 2;
    this.design.visible = false;
    this.world.add(this.design);
  }

  buildStock() {
    this.stock = null;
    const s = this.model.stock;
    if (!s) return;
    const mat = new LineBasicMaterial({ color: STOCK_COLOR, transparent: true, opacity: 0.85 });
    if (s.box) {
      const min = new Vector3(...s.box.min);
      const max = new Vector3(...s.box.max);
      const size = max.clone().sub(min);
      const box = new BoxGeometry(Math.max(size.x, 1e-6), Math.max(size.y, 1e-6), Math.max(size.z, 1e-6));
      this.stock = new LineSegments(new EdgesGeometry(box), mat);
      this.stock.position.copy(min.clone().add(max).multiplyScalar(0.5));
      box.dispose();
    } else if (s.mesh) {
      const g = geometryFrom(s.mesh, false);
      if (s.mesh.triangles <= 400000) {
        this.stock = new LineSegments(new EdgesGeometry(g, 25), mat);
        this.stock.geometry.computeBoundingBox();
        g.dispose();
      } else {
        this.stock = new Mesh(g, new MeshBasicMaterial({ color: STOCK_COLOR, wireframe: true, transparent: true, opacity: 0.25 }));
      }
    }
    if (this.stock) {
      this.stock.visible = false;
      this.stock.renderOrder = 3;
      this.world.add(this.stock);
    }
  }

  buildMarker() {
    const group = new Group();
    const matFront = new MeshBasicMaterial({ color: MARKER_COLOR, depthTest: false, transparent: true, opacity: 0.95 });
    const head = new Mesh(new SphereGeometry(1, 20, 14), matFront);
    head.position.set(0, 0, 9);
    const tip = new Mesh(new SphereGeometry(0.45, 16, 10), matFront);
    const stemGeom = new BufferGeometry();
    stemGeom.setAttribute('position', new Float32BufferAttribute([0, 0, 0, 0, 0, 9], 3));
    const stem = new LineSegments(stemGeom, new LineBasicMaterial({ color: MARKER_COLOR, depthTest: false, transparent: true }));
    group.add(stem, head, tip);
    group.traverse((o) => { o.renderOrder = 10; });
    group.visible = false;
    this.marker = group;
    this.world.add(group);
  }

  buildRegionMarkers() {
    this.regionPoints = null;
    const regions = this.model.regions || [];
    const pts = [];
    const cols = [];
    for (const r of regions.slice(0, 2000)) {
      const p = r.deepest || r.centroid;
      if (!Array.isArray(p) || p.length < 3) continue;
      pts.push(p[0], p[1], p[2]);
      if (r.kind === 'gouge') cols.push(0.95, 0.16, 0.16);
      else cols.push(0.2, 0.45, 1.0);
    }
    if (pts.length === 0) return;
    const g = new BufferGeometry();
    g.setAttribute('position', new Float32BufferAttribute(pts, 3));
    g.setAttribute('color', new Float32BufferAttribute(cols, 3));
    const mat = new PointsMaterial({
      size: 13, sizeAttenuation: false, vertexColors: true, map: roundSpriteTexture(),
      transparent: true, alphaTest: 0.3, depthTest: false,
    });
    this.regionPoints = new Points(g, mat);
    this.regionPoints.renderOrder = 9;
    this.world.add(this.regionPoints);
  }

  buildTriad() {
    const scene = new Scene();
    const g = new BufferGeometry();
    g.setAttribute('position', new Float32BufferAttribute([0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1], 3));
    g.setAttribute('color', new Float32BufferAttribute([1, 0.3, 0.3, 1, 0.3, 0.3, 0.4, 0.9, 0.4, 0.4, 0.9, 0.4, 0.45, 0.6, 1, 0.45, 0.6, 1], 3));
    scene.add(new LineSegments(g, new LineBasicMaterial({ vertexColors: true })));
    const heads = [[1, 0, 0, 0xff5050], [0, 1, 0, 0x66e066], [0, 0, 1, 0x7399ff]];
    for (const [x, y, z, c] of heads) {
      const s = new Mesh(new SphereGeometry(0.07, 10, 8), new MeshBasicMaterial({ color: c }));
      s.position.set(x, y, z);
      scene.add(s);
    }
    const cam = new OrthographicCamera(-1.45, 1.45, 1.45, -1.45, 0.1, 10);
    cam.up.set(0, 0, 1);
    this.triad = { scene, camera: cam, size: 96, labels: {} };
    for (const a of ['X', 'Y', 'Z']) {
      const l = el('div', { class: `triad-label triad-${a.toLowerCase()}`, text: a });
      this.container.append(l);
      this.triad.labels[a] = l;
    }
  }

  // ---- toggles -------------------------------------------------------------------------

  setColorByDeviation(on) {
    if (!this.part || !this.hasDeviation) return;
    this.colorByDeviation = on;
    const mat = this.part.material;
    mat.vertexColors = on;
    mat.color.set(on ? 0xffffff : PLAIN_COLOR);
    mat.needsUpdate = true;
    this.requestRender();
  }

  setDesignVisible(on) {
    if (this.design) this.design.visible = on;
    this.requestRender();
  }

  setStockVisible(on) {
    if (this.stock) this.stock.visible = on;
    this.requestRender();
  }

  setRegionMarkersVisible(on) {
    if (this.regionPoints) this.regionPoints.visible = on;
    this.requestRender();
  }

  setMarker(p) {
    if (!p) this.marker.visible = false;
    else {
      this.marker.position.set(p[0], p[1], p[2]);
      this.marker.visible = true;
    }
    this.requestRender();
  }

  // Where the workpiece frame stands in the view (a Matrix4); with `follow` the camera moves
  // with it, keeping its view of what it looks at.
  setWorldMatrix(matrix, follow = false) {
    if (follow) {
      const delta = matrix.clone().multiply(this.world.matrix.clone().invert());
      this.camera.position.applyMatrix4(delta);
      this.controls.target.applyMatrix4(delta);
      this.controls.update();
    }
    this.world.matrix.copy(matrix);
    this.world.matrixWorldNeedsUpdate = true;
    this.requestRender();
  }

  // ---- camera --------------------------------------------------------------------------

  cameraState() {
    const p = this.camera.position;
    const t = this.controls.target;
    return { position: [p.x, p.y, p.z], target: [t.x, t.y, t.z] };
  }

  isAnimating() {
    return this.anim != null;
  }

  cancelAnimation() {
    if (this.anim) {
      this.anim = null;
      this.controls.enabled = true;
    }
  }

  animateTo(target, dir, dist, animate = true) {
    const fromTarget = this.controls.target.clone();
    const offset = this.camera.position.clone().sub(fromTarget);
    const fromDist = Math.max(offset.length(), 1e-9);
    const fromDir = offset.divideScalar(fromDist);
    const toDir = dir.clone().normalize();
    if (!animate) {
      this.controls.target.copy(target);
      this.camera.position.copy(target).addScaledVector(toDir, dist);
      this.camera.lookAt(target);
      this.controls.update();
      this.requestRender();
      return;
    }
    this.anim = {
      start: performance.now(), fromTarget, toTarget: target.clone(), fromDir, toDir,
      fromDist, toDist: dist,
    };
    this.controls.enabled = false;
    this.requestRender();
  }

  stepAnimation(now) {
    const a = this.anim;
    const u = Math.min(1, (now - a.start) / FLY_MS);
    const t = easeInOutCubic(u);
    const target = a.fromTarget.clone().lerp(a.toTarget, t);
    let dir = a.fromDir.clone().lerp(a.toDir, t);
    if (dir.lengthSq() < 1e-8) dir = a.toDir.clone();
    dir.normalize();
    const dist = Math.exp(Math.log(a.fromDist) + (Math.log(a.toDist) - Math.log(a.fromDist)) * t);
    this.controls.target.copy(target);
    this.camera.position.copy(target).addScaledVector(dir, dist);
    this.camera.lookAt(target);
    if (u >= 1) {
      this.anim = null;
      this.controls.enabled = true;
      this.controls.update();
    }
  }

  fitDistance() {
    const fov = (this.camera.fov * Math.PI) / 180;
    const aspect = Math.max(this.camera.aspect, 0.2);
    const fovH = 2 * Math.atan(Math.tan(fov / 2) * aspect);
    const half = Math.min(fov, fovH) / 2;
    return (this.radius / Math.sin(half)) * 0.92;
  }

  // Standard views: 'iso', 'top', 'front', 'right', 'left', 'back'; frames the whole part.
  setView(name, animate = true) {
    const d = VIEW_DIRS[name] || VIEW_DIRS.iso;
    const center = this.bounds.getCenter(new Vector3()).applyMatrix4(this.world.matrix);
    this.animateTo(center, new Vector3(...d), this.fitDistance(), animate);
  }

  // Flies to a point, keeping the view direction, and closes in on it.
  flyTo(p, animate = true) {
    if (!Array.isArray(p) || p.length < 3 || !p.every(Number.isFinite)) return false;
    const target = new Vector3(p[0], p[1], p[2]).applyMatrix4(this.world.matrix);
    const offset = this.camera.position.clone().sub(this.controls.target);
    let dist = offset.length();
    const close = Math.max(this.radius * 0.7, 2);
    if (!(dist < close)) dist = close;
    if (offset.lengthSq() < 1e-12) offset.set(...VIEW_DIRS.iso);
    this.animateTo(target, offset, dist, animate);
    return true;
  }

  // ---- picking -------------------------------------------------------------------------

  installPicking() {
    const canvas = this.renderer.domElement;
    let down = null;
    canvas.addEventListener('pointerdown', (e) => {
      down = e.button === 0 ? { x: e.clientX, y: e.clientY } : null;
    });
    canvas.addEventListener('pointerup', (e) => {
      if (!down || e.button !== 0) return;
      const moved = Math.hypot(e.clientX - down.x, e.clientY - down.y);
      down = null;
      if (moved > CLICK_SLOP_PX) return;
      this.onPick(this.pick(e.clientX, e.clientY));
    });
    canvas.addEventListener('dblclick', (e) => {
      const hit = this.pick(e.clientX, e.clientY);
      if (hit) this.animateTo(new Vector3(...hit.point).applyMatrix4(this.world.matrix), this.camera.position.clone().sub(this.controls.target),
        this.camera.position.distanceTo(this.controls.target));
    });
    this.raycaster = new Raycaster();
  }

  pick(clientX, clientY) {
    if (!this.part) return null;
    const r = this.renderer.domElement.getBoundingClientRect();
    const ndc = new Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
    this.raycaster.setFromCamera(ndc, this.camera);
    const hits = this.raycaster.intersectObject(this.part, false);
    if (hits.length === 0) return null;
    const h = hits[0];
    h.point = this.world.worldToLocal(h.point.clone()); // workpiece frame
    const m = this.model.mesh;
    const pos = m.positions;
    // The face vertex nearest the hit carries the deviation and source shown.
    let best = h.face.a;
    let bestD = Infinity;
    for (const v of [h.face.a, h.face.b, h.face.c]) {
      const dx = pos[v * 3] - h.point.x, dy = pos[v * 3 + 1] - h.point.y, dz = pos[v * 3 + 2] - h.point.z;
      const d = dx * dx + dy * dy + dz * dz;
      if (d < bestD) { bestD = d; best = v; }
    }
    const dev = m.deviation ? m.deviation[best] : NaN;
    const src = m.source ? m.source[best] : null;
    return {
      point: [h.point.x, h.point.y, h.point.z],
      vertex: best,
      deviation: Number.isFinite(dev) ? dev : null,
      source: src,
    };
  }

  // ---- rendering -----------------------------------------------------------------------

  resize() {
    const w = Math.max(1, this.container.clientWidth);
    const h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  requestRender() {
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame((now) => this.frame(now));
  }

  frame(now) {
    this.frameRequested = false;
    if (this.anim) this.stepAnimation(now);
    this.render();
    if (this.anim) this.requestRender();
    if (!this.firstFrameDone) {
      this.firstFrameDone = true;
      // One more frame so the first image has been presented, then report ready.
      requestAnimationFrame(() => {
        for (const cb of this.readyCallbacks) cb();
        this.readyCallbacks = [];
      });
    }
  }

  whenFirstFrame(cb) {
    if (this.firstFrameDone && this.readyCallbacks.length === 0) cb();
    else this.readyCallbacks.push(cb);
  }

  render() {
    const cam = this.camera;
    const dist = cam.position.distanceTo(this.controls.target);
    // Near/far follow the zoom so close-ups of a 0.02 mm gouge keep their depth precision.
    cam.near = Math.max(dist / 1000, this.sceneRadius * 1e-6);
    cam.far = dist + this.sceneRadius * 6;
    cam.updateProjectionMatrix();

    const markerScale = dist * 0.006;
    this.marker.scale.setScalar(markerScale);

    const r = this.renderer;
    const w = r.domElement.width / r.getPixelRatio();
    const h = r.domElement.height / r.getPixelRatio();
    r.setViewport(0, 0, w, h);
    r.setScissorTest(false);
    r.render(this.scene, cam);

    // Orientation triad, bottom right.
    const t = this.triad;
    const s = t.size;
    const dir = cam.position.clone().sub(this.controls.target).normalize();
    t.camera.position.copy(dir).multiplyScalar(4);
    t.camera.quaternion.copy(cam.quaternion);
    t.camera.updateMatrixWorld();
    r.autoClear = false;
    r.clearDepth();
    r.setViewport(w - s - 8, 8, s, s);
    r.render(t.scene, t.camera);
    r.setViewport(0, 0, w, h);
    r.autoClear = true;
    const axes = { X: [1.22, 0, 0], Y: [0, 1.22, 0], Z: [0, 0, 1.22] };
    for (const [a, v] of Object.entries(axes)) {
      const p = new Vector3(...v).project(t.camera);
      const x = w - s - 8 + ((p.x + 1) / 2) * s;
      const y = h - 8 - ((p.y + 1) / 2) * s;
      t.labels[a].style.transform = `translate(${x.toFixed(1)}px, ${y.toFixed(1)}px) translate(-50%, -50%)`;
    }
  }

  showOverlayError(msg) {
    this.container.append(el('div', { class: 'view-error', text: msg }));
  }
}

export { NO_DATA };
