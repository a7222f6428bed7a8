// The viewer page's own script (src/knit/present/viewer.hpp; built into knitsim as a string by
// CMakeLists.txt, so the page stays one file): decode the frames, build a tube per yarn and a
// mesh per scene object, update them per frame, and keep the scale bar true to the camera.
"use strict";
const data = JSON.parse(document.getElementById("knitsim-data").textContent);
function bytesOf(b64) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return bytes.buffer;
}
const decode = (b64) => new Float32Array(bytesOf(b64));
const Q = decode(data.positions);
const NCP = data.counts.reduce((a, b) => a + b, 0);
const S = data.samples, SIDES = data.sides;
const PALETTE = [[0.80, 0.36, 0.25], [0.88, 0.66, 0.30], [0.45, 0.62, 0.38],
                 [0.30, 0.52, 0.72], [0.55, 0.40, 0.68], [0.78, 0.45, 0.58]];

const canvas = document.getElementById("view");
const renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true,
                                          preserveDrawingBuffer: true});
renderer.setPixelRatio(window.devicePixelRatio || 1);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f1ea);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8070, 0.75));
const sun = new THREE.DirectionalLight(0xffffff, 0.75);
scene.add(sun);
const camera = new THREE.PerspectiveCamera(35, 1, 0.01, 1e5);
camera.up.set(0, 0, 1);  // knitsim's +z is up (see below for flat knits)

// one tube per yarn: rings of SIDES vertices around S samples per segment
const yarns = [];
let cpBegin = 0, segBegin = 0;
for (let y = 0; y < data.counts.length; ++y) {
  const n = data.counts[y], nseg = n - 3, ns = nseg * S + 1;
  const pos = new Float32Array(ns * SIDES * 3), nrm = new Float32Array(ns * SIDES * 3);
  const col = new Float32Array(ns * SIDES * 3);
  for (let k = 0; k < ns; ++k) {
    const seg = segBegin + Math.min(Math.floor(k / S), nseg - 1);
    const key = data.rows.length ? data.rows[seg] : y;
    const c = PALETTE[((key % 6) + 6) % 6];
    for (let s = 0; s < SIDES; ++s) col.set(c, 3 * (k * SIDES + s));
  }
  const index = [];
  for (let k = 0; k + 1 < ns; ++k)
    for (let s = 0; s < SIDES; ++s) {
      const a = k * SIDES + s, b = k * SIDES + (s + 1) % SIDES, c = a + SIDES, d = b + SIDES;
      index.push(a, b, d, a, d, c);
    }
  const geom = new THREE.BufferGeometry();
  geom.setIndex(index);
  geom.setAttribute("position", new THREE.BufferAttribute(pos, 3));
  geom.setAttribute("normal", new THREE.BufferAttribute(nrm, 3));
  geom.setAttribute("color", new THREE.BufferAttribute(col, 3));
  const mesh = new THREE.Mesh(geom, new THREE.MeshStandardMaterial(
      {vertexColors: THREE.VertexColors, roughness: 0.85, metalness: 0.0}));
  scene.add(mesh);
  yarns.push({geom: geom, pos: pos, nrm: nrm, cp: cpBegin, nseg: nseg, ns: ns,
              r: data.radius[y], p: new Float64Array(ns * 3)});
  cpBegin += n;
  segBegin += nseg;
}

// the scene's objects: each one's surface in its own frame, placed by its pose per frame
// (x, y, z, then the rotation's quaternion x, y, z, w; one pose when it does not move), in
// the renderer's grey
const objects = [];
const objectMaterial = new THREE.MeshStandardMaterial(
    {color: 0x9aa7b2, roughness: 0.9, metalness: 0.0, side: THREE.DoubleSide});
for (const o of data.objects) {
  const geom = new THREE.BufferGeometry();
  geom.setIndex(new THREE.BufferAttribute(new Uint32Array(bytesOf(o.triangles)), 1));
  geom.setAttribute("position", new THREE.BufferAttribute(decode(o.vertices), 3));
  geom.computeVertexNormals();
  const mesh = new THREE.Mesh(geom, objectMaterial);
  mesh.name = o.name;
  scene.add(mesh);
  objects.push({mesh: mesh, poses: o.poses});
}
document.body.dataset.objects = String(objects.length);

// the cubic B-spline's samples, then rings carried along by parallel transport
function setFrame(f) {
  const base = f * 3 * NCP;
  for (const Y of yarns) {
    const p = Y.p;
    for (let k = 0; k < Y.ns; ++k) {
      const i = Math.min(Math.floor(k / S), Y.nseg - 1), t = k / S - i;
      const t2 = t * t, t3 = t2 * t;
      const b = [(1 - t) * (1 - t) * (1 - t) / 6, (3 * t3 - 6 * t2 + 4) / 6,
                 (-3 * t3 + 3 * t2 + 3 * t + 1) / 6, t3 / 6];
      for (let c = 0; c < 3; ++c) {
        let v = 0;
        for (let j = 0; j < 4; ++j) v += b[j] * Q[base + 3 * (Y.cp + i + j) + c];
        p[3 * k + c] = v;
      }
    }
    let ux = 0, uy = 0, uz = 0;
    for (let k = 0; k < Y.ns; ++k) {
      const a = Math.max(k - 1, 0), e = Math.min(k + 1, Y.ns - 1);
      let tx = p[3 * e] - p[3 * a], ty = p[3 * e + 1] - p[3 * a + 1], tz = p[3 * e + 2] - p[3 * a + 2];
      const tl = Math.hypot(tx, ty, tz) || 1;
      tx /= tl; ty /= tl; tz /= tl;
      if (k === 0) {  // any normal to start
        if (Math.abs(tx) < 0.9) { ux = 0; uy = tz; uz = -ty; } else { ux = -tz; uy = 0; uz = tx; }
      }
      const d = ux * tx + uy * ty + uz * tz;
      ux -= d * tx; uy -= d * ty; uz -= d * tz;
      const ul = Math.hypot(ux, uy, uz) || 1;
      ux /= ul; uy /= ul; uz /= ul;
      const wx = ty * uz - tz * uy, wy = tz * ux - tx * uz, wz = tx * uy - ty * ux;
      for (let s = 0; s < SIDES; ++s) {
        const ang = 2 * Math.PI * s / SIDES, ca = Math.cos(ang), sa = Math.sin(ang);
        const nx = ca * ux + sa * wx, ny = ca * uy + sa * wy, nz = ca * uz + sa * wz;
        const o = 3 * (k * SIDES + s);
        Y.pos[o] = p[3 * k] + Y.r * nx;
        Y.pos[o + 1] = p[3 * k + 1] + Y.r * ny;
        Y.pos[o + 2] = p[3 * k + 2] + Y.r * nz;
        Y.nrm[o] = nx; Y.nrm[o + 1] = ny; Y.nrm[o + 2] = nz;
      }
    }
    Y.geom.attributes.position.needsUpdate = true;
    Y.geom.attributes.normal.needsUpdate = true;
    Y.geom.computeBoundingSphere();
  }
  for (const O of objects) {
    const q = O.poses[Math.min(f, O.poses.length - 1)];
    O.mesh.position.set(q[0], q[1], q[2]);
    O.mesh.quaternion.set(q[3], q[4], q[5], q[6]);
  }
  const time = data.times[f];
  document.getElementById("time").textContent =
      "t = " + time.toFixed(3) + " s   (frame " + (f + 1) + " of " + data.times.length + ")";
}

// the camera frames data.box (every frame's yarn and bounded objects, as `knitsim render`
// frames them): a flat knit alone (thin in z) from its front face, a little tilted, with its
// wale up; anything else, and a knit among objects, from the front and above, z up
const box = new THREE.Box3(new THREE.Vector3().fromArray(data.box, 0),
                           new THREE.Vector3().fromArray(data.box, 3));
const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
const extent = Math.max(size.x, size.y, size.z, 1e-3);
const flat = objects.length === 0 && size.z < 0.5 * Math.min(size.x, size.y);
if (flat) camera.up.set(0, 1, 0);
// far enough that the box's width and height fit the view, with a margin; `zoom` (the
// address's #zoom=Z) goes Z times closer
function frameCamera(zoom) {
  const tan = Math.tan(camera.fov * Math.PI / 360);
  const w = flat ? size.x : Math.hypot(size.x, size.y), h = flat ? size.y : size.z + 0.5 * size.y;
  const d = 1.15 * Math.max(h / 2, w / 2 / camera.aspect) / tan + (flat ? size.z : 0.5 * extent);
  const dir = flat ? new THREE.Vector3(0.12, -0.25, 1) : new THREE.Vector3(0.2, -1.9, 0.9);
  dir.normalize();
  camera.position.copy(centre).addScaledVector(dir, d / zoom);
}
camera.near = extent / 100;
camera.far = extent * 100;
sun.position.set(centre.x + extent, centre.y - 2 * extent, centre.z + 3 * extent);
const controls = new THREE.OrbitControls(camera, canvas);
controls.target.copy(centre);
controls.update();

// the scale bar: a round length (1, 2 or 5 × 10^k cm) at most a quarter of the view wide,
// measured at the depth of the orbit's centre (as `knitsim render` measures its bar at the
// framed box's centre), redrawn with every change of the camera
const scaleBox = document.getElementById("scale");
function updateScaleBar() {
  const forward = camera.getWorldDirection(new THREE.Vector3());
  const depth = Math.max(controls.target.clone().sub(camera.position).dot(forward), 1e-9);
  const pxPerCm = canvas.clientHeight / (2 * depth * Math.tan(camera.fov * Math.PI / 360));
  let length = 0;
  for (let k = -3; k <= 4; ++k)
    for (const m of [1, 2, 5])
      if (m * Math.pow(10, k) * pxPerCm <= 0.25 * canvas.clientWidth) length = m * Math.pow(10, k);
  const px = length * pxPerCm;
  scaleBox.style.display = length > 0 && px >= 4 ? "" : "none";
  const round = (x) => String(Number(x.toPrecision(3)));
  document.getElementById("scale-label").textContent =
      length >= 1 ? round(length) + " cm" : round(10 * length) + " mm";
  document.getElementById("scale-bar").style.width = px.toFixed(1) + "px";
  scaleBox.dataset.cm = String(length);
  scaleBox.dataset.pxPerCm = pxPerCm.toFixed(3);
  scaleBox.dataset.view = canvas.clientWidth + "x" + canvas.clientHeight;
}

const slider = document.getElementById("frame");
slider.max = String(data.times.length - 1);
let frame = 0, playing = false, clock = null;
function show(f) {
  frame = f;
  slider.value = String(f);
  setFrame(f);
  draw();
}
function resize() {
  const w = canvas.clientWidth, h = canvas.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
function draw() {
  renderer.render(scene, camera);
  updateScaleBar();
}
slider.addEventListener("input", () => { playing = false; updateButton(); show(Number(slider.value)); });
controls.addEventListener("change", draw);
// until the camera is moved, a resized window frames the knit anew
let moved = false;
controls.addEventListener("start", () => { moved = true; });
window.addEventListener("resize", () => {
  resize();
  if (!moved) {
    frameCamera(zoom);
    controls.update();
  }
  draw();
});
const button = document.getElementById("play");
function updateButton() { button.textContent = playing ? "pause" : "play"; }
button.addEventListener("click", () => {
  playing = !playing && data.times.length > 1;
  if (playing && frame === data.times.length - 1) show(0);
  clock = null;
  updateButton();
  if (playing) requestAnimationFrame(tick);
});
// playback at the simulation's real time (times in seconds), looping
function tick(now) {
  if (!playing) return;
  if (clock === null) clock = {wall: now, sim: data.times[frame]};
  const sim = clock.sim + (now - clock.wall) / 1000 * data.speed;
  let f = frame;
  while (f + 1 < data.times.length && data.times[f + 1] <= sim) ++f;
  if (f === data.times.length - 1 && sim > data.times[f]) { show(f); playing = false; updateButton(); return; }
  if (f !== frame) show(f);
  requestAnimationFrame(tick);
}
resize();
const zoomed = /zoom=([0-9.]+)/.exec(window.location.hash);
const zoom = zoomed && Number(zoomed[1]) > 0 ? Number(zoomed[1]) : 1;
frameCamera(zoom);
controls.update();
const wanted = /frame=(\d+)/.exec(window.location.hash);
show(wanted ? Math.min(Number(wanted[1]), data.times.length - 1) : 0);
window.knitsimReady = true;
