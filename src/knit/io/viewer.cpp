#include "knit/io/viewer.hpp"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "knit/io/states.hpp"

namespace knit {

namespace {

std::string base64(const unsigned char* data, size_t size) {
  static const char* table = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (size_t i = 0; i < size; i += 3) {
    const unsigned a = data[i], b = i + 1 < size ? data[i + 1] : 0,
                   c = i + 2 < size ? data[i + 2] : 0;
    const unsigned n = (a << 16) | (b << 8) | c;
    out += table[(n >> 18) & 63];
    out += table[(n >> 12) & 63];
    out += i + 1 < size ? table[(n >> 6) & 63] : '=';
    out += i + 2 < size ? table[n & 63] : '=';
  }
  return out;
}

std::string read_script(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw std::runtime_error("viewer: " + path.string() +
                             " is missing: install Debian's libjs-three (scripts/setup.sh does)");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string s = ss.str();
  // nothing in a script may end the <script> element early
  for (size_t at = 0; (at = s.find("</script", at)) != std::string::npos; at += 2)
    s.replace(at, 2, "<\\/");
  return s;
}

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

// The page's own script: decode the frames, build a tube per yarn, update it per frame.
const char* const VIEWER_JS = R"JS(
"use strict";
const data = JSON.parse(document.getElementById("knitsim-data").textContent);
function decode(b64) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; ++i) bytes[i] = bin.charCodeAt(i);
  return new Float32Array(bytes.buffer);
}
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
  const time = data.times[f];
  document.getElementById("time").textContent =
      "t = " + time.toFixed(3) + " s   (frame " + (f + 1) + " of " + data.times.length + ")";
}

// the camera frames every frame (the control points' box holds the curves): a flat knit
// (thin in z) from its front face, a little tilted, with its wale up; anything else from the
// front and above, z up
const box = new THREE.Box3();
const rmax = Math.max.apply(null, data.radius);
for (let i = 0; i + 2 < Q.length; i += 3)
  box.expandByPoint(new THREE.Vector3(Q[i], Q[i + 1], Q[i + 2]));
box.expandByScalar(rmax);
const centre = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
const extent = Math.max(size.x, size.y, size.z, 1e-3);
const flat = size.z < 0.5 * Math.min(size.x, size.y);
if (flat) camera.up.set(0, 1, 0);
// far enough that the box's width and height fit the view, with a margin
function frameCamera() {
  const tan = Math.tan(camera.fov * Math.PI / 360);
  const w = flat ? size.x : Math.hypot(size.x, size.y), h = flat ? size.y : size.z + 0.5 * size.y;
  const d = 1.15 * Math.max(h / 2, w / 2 / camera.aspect) / tan + (flat ? size.z : 0.5 * extent);
  const dir = flat ? new THREE.Vector3(0.12, -0.25, 1) : new THREE.Vector3(0.2, -1.9, 0.9);
  dir.normalize();
  camera.position.copy(centre).addScaledVector(dir, d);
}
camera.near = extent / 100;
camera.far = extent * 100;
sun.position.set(centre.x + extent, centre.y - 2 * extent, centre.z + 3 * extent);
const controls = new THREE.OrbitControls(camera, canvas);
controls.target.copy(centre);
controls.update();

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
function draw() { renderer.render(scene, camera); }
slider.addEventListener("input", () => { playing = false; updateButton(); show(Number(slider.value)); });
controls.addEventListener("change", draw);
window.addEventListener("resize", () => { resize(); draw(); });
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
frameCamera();
controls.update();
const wanted = /frame=(\d+)/.exec(window.location.hash);
show(wanted ? Math.min(Number(wanted[1]), data.times.length - 1) : 0);
window.knitsimReady = true;
)JS";

}  // namespace

std::string viewer_html(const std::vector<StateFile>& frames, const std::vector<double>& times,
                        const ViewerOptions& o) {
  check_state_sequence(frames, times, "viewer");
  if (o.samples_per_segment < 1 || o.samples_per_segment > 64)
    throw std::invalid_argument("viewer: samples per segment must be in [1, 64]");
  if (o.sides < 3 || o.sides > 64) throw std::invalid_argument("viewer: sides must be in [3, 64]");
  const size_t ncp = static_cast<size_t>(frames[0].num_cp());
  const long long bytes = static_cast<long long>(frames.size() * ncp * 12 * 4 / 3);
  if (bytes > o.max_bytes)
    throw std::runtime_error("viewer: " + std::to_string(frames.size()) + " frames of " +
                             std::to_string(ncp) + " control points make a page of about " +
                             std::to_string(bytes >> 20) + " MB; show fewer frames (every Nth)");
  const std::filesystem::path dir(o.three_dir);
  const std::string three = read_script(dir / "three.min.js");
  const std::string orbit = read_script(dir / "examples/js/controls/OrbitControls.js");

  std::vector<float> q;
  q.reserve(frames.size() * 3 * ncp);
  for (const StateFile& f : frames)
    for (Eigen::Index k = 0; k < f.state.q.size(); ++k)
      q.push_back(static_cast<float>(f.state.q[k]));
  nlohmann::json d;
  d["counts"] = frames[0].yarn_cp_counts;
  d["radius"] = frames[0].yarn_radius;
  d["times"] = times;
  d["samples"] = o.samples_per_segment;
  d["sides"] = o.sides;
  d["speed"] = 1.0;
  std::vector<int> rows;
  if (frames[0].stitch.size() == static_cast<size_t>(frames[0].num_seg()))
    for (const StitchCoord& s : frames[0].stitch) rows.push_back(s.row);
  d["rows"] = rows;
  d["positions"] =
      base64(reinterpret_cast<const unsigned char*>(q.data()), q.size() * sizeof(float));

  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<title>" + html_escape(o.title) + "</title>\n";
  html += "<meta name=\"generator\" content=\"knitsim " KNIT_VERSION "\">\n";
  html +=
      "<style>\n"
      "html, body { margin: 0; height: 100%; overflow: hidden; font: 14px system-ui, "
      "sans-serif; background: #f4f1ea; }\n"
      "#view { display: block; width: 100%; height: calc(100% - 44px); }\n"
      "#bar { height: 44px; display: flex; align-items: center; gap: 12px; padding: 0 12px; "
      "box-sizing: border-box; }\n"
      "#frame { flex: 1; min-width: 60px; }\n"
      "#time, #title { white-space: nowrap; }\n"
      "#title { font-weight: 600; }\n"
      "</style>\n</head>\n<body>\n<canvas id=\"view\"></canvas>\n";
  html += "<div id=\"bar\"><span id=\"title\">" + html_escape(o.title) +
          "</span><button id=\"play\">play</button><input id=\"frame\" type=\"range\" min=\"0\" "
          "max=\"0\" step=\"1\" value=\"0\"><span id=\"time\"></span></div>\n";
  html += "<script type=\"application/json\" id=\"knitsim-data\">" + d.dump() + "</script>\n";
  html += "<script>\n" + three + "\n</script>\n";
  html += "<script>\n" + orbit + "\n</script>\n";
  html += "<script>\n";
  html += VIEWER_JS;
  html += "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace knit
