// The browser viewer: the page carries the frames, a scene's objects and three.js, and
// headless Chromium shows yarn in it, a different picture at another frame, the objects, and
// a scale bar that measures them at any zoom.
#include "knit/present/viewer.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <nlohmann/json.hpp>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#include "io/external_readers.hpp"
#include "io/test_states.hpp"
#include "knit/objects/shape.hpp"
#include "knit/util/atomic_file.hpp"

namespace knit {
namespace {

std::vector<unsigned char> unbase64(const std::string& s) {
  std::vector<unsigned char> out;
  unsigned buffer = 0;
  int bits = 0;
  for (char c : s) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (v < 0) continue;
    buffer = (buffer << 6) | static_cast<unsigned>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<unsigned char>((buffer >> bits) & 0xff));
    }
  }
  return out;
}

// two frames of a helix: the second turned a quarter about z and moved along it
std::vector<StateFile> two_frames() {
  StateFile a = test::state_of({test::helix_control_points(1.0, 1.0, 3, 24)}, 0.125, 0.0, true);
  StateFile b = a;
  b.state.time = 0.5;
  for (int k = 0; k < b.num_cp(); ++k) {
    const Eigen::Vector3d p = a.state.q.segment<3>(3 * k);
    b.state.q.segment<3>(3 * k) = Eigen::Vector3d(-p.y(), p.x(), p.z() + 0.5);
  }
  return {a, b};
}

nlohmann::json page_data(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"knitsim-data\">";
  const size_t at = html.find(open);
  if (at == std::string::npos) return {};
  const size_t begin = at + open.size();
  return nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
}

template <class T>
std::vector<T> decoded(const nlohmann::json& b64) {
  const auto bytes = unbase64(b64.get<std::string>());
  std::vector<T> out(bytes.size() / sizeof(T));
  std::memcpy(out.data(), bytes.data(), out.size() * sizeof(T));
  return out;
}

std::shared_ptr<const SceneObject> object(const std::string& name, ShapePtr shape,
                                          Eigen::Vector3d position = Eigen::Vector3d::Zero()) {
  auto o = std::make_shared<SceneObject>();
  o->name = name;
  o->shape = std::move(shape);
  o->position = position;
  return o;
}

TEST(Viewer, ThePageCarriesTheFramesAndThreeJs) {
  const auto frames = two_frames();
  const std::string html = viewer_html(frames, {0.0, 0.5});
  // self-contained: no file or network fetched by the page
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_NE(html.find("THREE.OrbitControls"), std::string::npos);
  const std::string open = "<script type=\"application/json\" id=\"knitsim-data\">";
  const size_t at = html.find(open);
  ASSERT_NE(at, std::string::npos);
  const size_t begin = at + open.size();
  const auto d = nlohmann::json::parse(html.substr(begin, html.find("</script>", begin) - begin));
  EXPECT_EQ(d["counts"], frames[0].yarn_cp_counts);
  EXPECT_EQ(d["times"], std::vector<double>({0.0, 0.5}));
  EXPECT_EQ(d["rows"].size(), static_cast<size_t>(frames[0].num_seg()));
  // the positions are both frames' control points, as float32
  const auto bytes = unbase64(d["positions"].get<std::string>());
  ASSERT_EQ(bytes.size(), 2 * frames[0].state.q.size() * sizeof(float));
  std::vector<float> q(bytes.size() / sizeof(float));
  std::memcpy(q.data(), bytes.data(), bytes.size());
  const Eigen::Index n = frames[0].state.q.size();
  for (int f = 0; f < 2; ++f)
    for (Eigen::Index k = 0; k < n; k += 5)
      EXPECT_NEAR(q[static_cast<size_t>(f * n + k)], frames[f].state.q[k], 1e-6);
}

// a ball that moves between the frames, a floor, and a floor far below the yarn: the page
// carries the ball's surface (in its own frame) with a pose per frame, the floor's slab with
// one pose, and leaves the far floor out
TEST(Viewer, ThePageCarriesTheObjectsSurfacesAndPoses) {
  const auto frames = two_frames();
  ViewerOptions o;
  auto ball = std::make_shared<SceneObject>();
  ball->name = "ball</script><b>";  // a name cannot end the page's data early
  ball->shape = make_sphere(Eigen::Vector3d::Zero(), 1.5);
  ball->position = Eigen::Vector3d(1.5, 0, -3);
  Keyframe k0, k1;
  k0.time = 0;
  k1.time = 0.5;
  k1.translation = Eigen::Vector3d(0, 0, 1);
  k1.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  ball->keyframes = {k0, k1};
  o.objects = {ball,
               object("floor", make_plane(Eigen::Vector3d(0, 0, -4.5), Eigen::Vector3d::UnitZ())),
               object("deep", make_plane(Eigen::Vector3d(0, 0, -500), Eigen::Vector3d::UnitZ()))};
  const std::string html = viewer_html(frames, {0.0, 0.5}, o);
  EXPECT_EQ(html.find("<b>"), std::string::npos) << "the object's name leaked into the page";
  const auto d = page_data(html);
  ASSERT_EQ(d["objects"].size(), 2u) << d["objects"];
  const auto& b = d["objects"][0];
  const auto& f = d["objects"][1];
  EXPECT_EQ(b["name"], ball->name);
  EXPECT_EQ(f["name"], "floor");
  // the ball's vertices lie on its sphere (its own frame), within a grid cell of it
  const auto v = decoded<float>(b["vertices"]);
  const auto t = decoded<uint32_t>(b["triangles"]);
  ASSERT_GT(t.size(), 300u);
  ASSERT_EQ(t.size() % 3, 0u);
  ASSERT_EQ(v.size() % 3, 0u);
  for (uint32_t i : t) ASSERT_LT(i, v.size() / 3);
  for (size_t i = 0; i < v.size(); i += 3)
    ASSERT_NEAR(std::hypot(v[i], v[i + 1], v[i + 2]), 1.5, 0.05) << "vertex " << i / 3;
  // its pose per frame: placed at its position, then raised 1 cm and turned a quarter
  ASSERT_EQ(b["poses"].size(), 2u);
  const std::vector<double> p0 = b["poses"][0], p1 = b["poses"][1];
  EXPECT_NEAR(p0[2], -3, 1e-9);
  EXPECT_NEAR(p0[6], 1, 1e-9);  // w: no turn
  EXPECT_NEAR(p1[0], 1.5, 1e-9);
  EXPECT_NEAR(p1[2], -2, 1e-9);
  EXPECT_NEAR(std::abs(p1[5]), std::sqrt(0.5), 1e-9);  // z of a quarter turn about z
  // the floor: one pose, its slab's top at the plane and wider than the yarn
  ASSERT_EQ(f["poses"].size(), 1u);
  const auto fv = decoded<float>(f["vertices"]);
  float top = -1e9f, xmin = 1e9f, xmax = -1e9f;
  for (size_t i = 0; i < fv.size(); i += 3) {
    top = std::max(top, fv[i + 2]);
    xmin = std::min(xmin, fv[i]);
    xmax = std::max(xmax, fv[i]);
  }
  EXPECT_NEAR(top, -4.5, 0.05);
  EXPECT_LT(xmin, -1);
  EXPECT_GT(xmax, 4);
  // the camera's box holds the yarn and the ball at both frames, not the floor
  const std::vector<double> box = d["box"];
  EXPECT_LT(box[2], -4.4);  // the ball's bottom at frame 0: -3 - 1.5
  EXPECT_GT(box[2], -4.6);
  EXPECT_GT(box[3], 3);  // the helix reaches x = 3
  // without objects: none on the page
  EXPECT_TRUE(page_data(viewer_html(frames, {0.0, 0.5}))["objects"].empty());
}

TEST(Viewer, BadFramesAndAMissingThreeJsAreNamed) {
  auto frames = two_frames();
  EXPECT_THROW(viewer_html({}, {}), std::invalid_argument);
  EXPECT_THROW(viewer_html(frames, {0.5, 0.5}), std::invalid_argument);
  ViewerOptions o;
  o.three_dir = "/nonexistent/three";
  try {
    viewer_html(frames, {0.0, 0.5}, o);
    FAIL() << "a page without three.js was written";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("libjs-three"), std::string::npos) << e.what();
  }
  o = ViewerOptions{};
  o.max_bytes = 100;
  EXPECT_THROW(viewer_html(frames, {0.0, 0.5}, o), std::runtime_error);
  frames[1] = test::state_of({test::helix_control_points(1, 1, 3, 20)});
  EXPECT_THROW(viewer_html(frames, {0.0, 0.5}), std::invalid_argument);
}

struct Shot {
  int width = 0, height = 0;
  std::vector<unsigned char> rgb;
};

// Headless Chromium's screenshot `png` of `url` in a window of width × height (software
// WebGL)
Shot screenshot_of(const std::string& chromium, const std::string& png, const std::string& url,
                   int width, int height) {
  std::string messages;
  const int rc =
      run_process({chromium, "--headless", "--no-sandbox", "--disable-gpu",
                   "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
                   "--window-size=" + std::to_string(width) + "," + std::to_string(height),
                   "--virtual-time-budget=3000", "--screenshot=" + png, url},
                  messages);
  EXPECT_EQ(rc, 0) << messages;
  Shot s;
  int channels = 0;
  unsigned char* pixels = stbi_load(png.c_str(), &s.width, &s.height, &channels, 3);
  EXPECT_NE(pixels, nullptr) << "no screenshot: " << messages;
  if (pixels) {
    s.rgb.assign(pixels, pixels + 3 * s.width * s.height);
    stbi_image_free(pixels);
  }
  return s;
}

// `page` opened at `frame`, 320 × 240
Shot screenshot(const std::string& chromium, const std::filesystem::path& dir,
                const std::string& page, int frame) {
  return screenshot_of(chromium, (dir / ("frame" + std::to_string(frame) + ".png")).string(),
                       "file://" + page + "#frame=" + std::to_string(frame), 320, 240);
}

TEST(Viewer, ChromiumShowsYarnAndTheFramesDiffer) {
  KNIT_REQUIRE_READER(chromium, "chromium", "chromium");
  const auto dir = test::temp_dir("viewer-chromium");
  const std::string page = (dir / "run.html").string();
  write_file_atomic(page, viewer_html(two_frames(), {0.0, 0.5}));
  const Shot a = screenshot(chromium, dir, page, 0), b = screenshot(chromium, dir, page, 1);
  ASSERT_EQ(a.width, 320);
  ASSERT_EQ(a.height, 240);
  ASSERT_EQ(b.rgb.size(), a.rgb.size());
  // the picture above the bar (44 px): yarn is whatever is far from the background colour
  const int rows = a.height - 44;
  long yarn = 0, changed = 0;
  for (int p = 0; p < a.width * rows; ++p) {
    const unsigned char* c = &a.rgb[static_cast<size_t>(3 * p)];
    const unsigned char* d = &b.rgb[static_cast<size_t>(3 * p)];
    if (std::abs(c[0] - 0xf4) + std::abs(c[1] - 0xf1) + std::abs(c[2] - 0xea) > 60) ++yarn;
    if (std::abs(c[0] - d[0]) + std::abs(c[1] - d[1]) + std::abs(c[2] - d[2]) > 60) ++changed;
  }
  const double area = static_cast<double>(a.width) * rows;
  EXPECT_GT(yarn / area, 0.02) << "hardly any yarn on the page";
  EXPECT_LT(yarn / area, 0.9) << "no background: is the camera inside the yarn?";
  EXPECT_GT(changed / area, 0.01) << "the second frame looks like the first";
}

// What the page reports in its DOM after its script ran (headless Chromium's --dump-dom).
// --dump-dom lays the page out in a window with room for a browser's own bars (and at least
// 500 px wide), unlike --screenshot: the page says the size of its picture (data-view), and
// a screenshot of that size (the page's bar below) shows what the DOM describes.
struct Report {
  std::string dom;
  int width = 0, height = 0;  ///< the window a screenshot needs for the same picture
};

Report report(const std::string& chromium, const std::string& url) {
  const std::string cmd = "'" + chromium +
                          "' --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader "
                          "--use-angle=swiftshader --window-size=500,400 "
                          "--virtual-time-budget=3000 --dump-dom '" +
                          url + "' 2>/dev/null";
  Report r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (size_t n = fread(buf.data(), 1, buf.size(), pipe)) r.dom.append(buf.data(), n);
  pclose(pipe);
  const size_t at = r.dom.find("data-view=\"");
  if (at != std::string::npos &&
      std::sscanf(r.dom.c_str() + at, "data-view=\"%dx%d\"", &r.width, &r.height) == 2)
    r.height += 44;
  return r;
}

// the value of attribute `name` of the first element that has it, or ""
std::string attribute(const std::string& html, const std::string& name) {
  const size_t at = html.find(" " + name + "=\"");
  if (at == std::string::npos) return "";
  const size_t begin = at + name.size() + 3;
  return html.substr(begin, html.find('"', begin) - begin);
}

// the text of the element with id `id`, or ""
std::string text_of(const std::string& html, const std::string& id) {
  const size_t at = html.find("id=\"" + id + "\"");
  if (at == std::string::npos) return "";
  const size_t begin = html.find('>', at) + 1;
  return html.substr(begin, html.find('<', begin) - begin);
}

// An object's pixel: far from the page's background and in the objects' grey (0x9aa7b2 lit,
// blue about red's height or above), not the yarn's red (a state without stitch rows is
// drawn in the palette's first colour, 0.80, 0.36, 0.25).
bool object_pixel(const unsigned char* c) {
  const bool background =
      std::abs(c[0] - 0xf4) + std::abs(c[1] - 0xf1) + std::abs(c[2] - 0xea) < 60;
  return !background && c[2] - c[0] > -15;
}

long object_pixels(const Shot& s) {
  long n = 0;
  for (int p = 0; p < s.width * (s.height - 44); ++p)
    n += object_pixel(&s.rgb[static_cast<size_t>(3 * p)]);
  return n;
}

// The length in pixels of the scale bar drawn: its bottom edge 56 px above the page's bottom,
// ending 12 px from the right (the page's style), dark
int drawn_bar(const Shot& s) {
  int longest = 0;
  for (int y = s.height - 60; y < s.height - 52; ++y) {
    int run = 0;
    for (int x = s.width - 13; x >= 0; --x) {
      const unsigned char* c = &s.rgb[static_cast<size_t>(3 * (y * s.width + x))];
      if (c[0] + c[1] + c[2] > 3 * 110) break;
      ++run;
    }
    longest = std::max(longest, run);
  }
  return longest;
}

// A ball under a helix and a floor below both: the page says it drew two objects and shows
// their grey, which the yarn alone's page has none of; the scale bar sits in the bottom
// right corner, as long as the page says, labelled with its length, the longest round length
// within a quarter of the picture's width.
TEST(Viewer, ChromiumShowsABallAndAFloorAndAScaleBar) {
  KNIT_REQUIRE_READER(chromium, "chromium", "chromium");
  const auto dir = test::temp_dir("viewer-objects");
  const StateFile yarn = test::helix_state();
  ViewerOptions o;
  o.objects = {object("ball", make_sphere(Eigen::Vector3d::Zero(), 1.2), {1.5, 0, -2.5}),
               object("floor", make_plane(Eigen::Vector3d(0, 0, -3.7), Eigen::Vector3d::UnitZ()))};
  const std::string with = (dir / "objects.html").string(), without = (dir / "yarn.html").string();
  write_file_atomic(with, viewer_html({yarn}, {0.0}, o));
  write_file_atomic(without, viewer_html({yarn}, {0.0}));
  const Report r = report(chromium, "file://" + with);
  EXPECT_EQ(attribute(r.dom, "data-objects"), "2") << r.dom.substr(0, 2000);
  const Report alone = report(chromium, "file://" + without);
  EXPECT_EQ(attribute(alone.dom, "data-objects"), "0");
  ASSERT_GT(r.width, 0) << "the page does not say its picture's size";

  const Shot a =
      screenshot_of(chromium, (dir / "objects.png").string(), "file://" + with, r.width, r.height);
  const Shot b =
      screenshot_of(chromium, (dir / "yarn.png").string(), "file://" + without, r.width, r.height);
  ASSERT_EQ(a.width, r.width);
  ASSERT_EQ(a.height, r.height);
  const double area = a.width * (a.height - 44.0);
  EXPECT_GT(object_pixels(a) / area, 0.15) << "hardly any object on the page";
  EXPECT_LT(object_pixels(b) / area, 0.005) << "the yarn alone looks like an object";

  const double cm = std::stod(attribute(r.dom, "data-cm"));
  const double px_per_cm = std::stod(attribute(r.dom, "data-px-per-cm"));
  EXPECT_EQ(text_of(r.dom, "scale-label"),
            cm >= 1 ? std::to_string(static_cast<int>(cm)) + " cm"
                    : std::to_string(static_cast<int>(std::lround(10 * cm))) + " mm");
  EXPECT_LE(cm * px_per_cm, 0.25 * a.width);
  EXPECT_GT(cm * px_per_cm, 0.25 * a.width / 2.5) << "not the longest round length that fits";
  EXPECT_NEAR(drawn_bar(a), cm * px_per_cm, 2.5) << "the bar drawn is not as long as it says";
  EXPECT_NEAR(drawn_bar(b),
              std::stod(attribute(alone.dom, "data-cm")) *
                  std::stod(attribute(alone.dom, "data-px-per-cm")),
              2.5);
}

// A ball of radius 1 cm at the orbit's centre, seen at two zooms: its height in pixels over
// the scale bar's pixels per centimetre is its diameter each time, and the bar drawn is as
// long as the page says.
TEST(Viewer, TheScaleBarMeasuresTheBallAtEveryZoom) {
  KNIT_REQUIRE_READER(chromium, "chromium", "chromium");
  const auto dir = test::temp_dir("viewer-scale");
  Eigen::Matrix3Xd line(3, 2);
  line.col(0) << -3, 0, 0;
  line.col(1) << 3, 0, 0;
  ViewerOptions o;
  o.objects = {object("ball", make_sphere(Eigen::Vector3d::Zero(), 1.0))};
  const std::string page = (dir / "ball.html").string();
  write_file_atomic(page, viewer_html({test::state_of({fit_polyline(line, 6)}, 0.1)}, {0.0}, o));
  double px_per_cm_at_1 = 0;
  for (const char* zoom : {"1", "2"}) {
    SCOPED_TRACE(std::string("zoom ") + zoom);
    const std::string url = "file://" + page + "#frame=0&zoom=" + zoom;
    const Report r = report(chromium, url);
    ASSERT_GT(r.width, 0) << "the page does not say its picture's size";
    const double cm = std::stod(attribute(r.dom, "data-cm"));
    const double px_per_cm = std::stod(attribute(r.dom, "data-px-per-cm"));
    const Shot s = screenshot_of(chromium, (dir / (std::string("zoom") + zoom + ".png")).string(),
                                 url, r.width, r.height);
    ASSERT_EQ(s.width, r.width);
    // the ball's tallest column (the yarn crosses its middle, in front)
    int tallest = 0;
    for (int x = 0; x < s.width; ++x) {
      int top = -1, bottom = -1;
      for (int y = 0; y < s.height - 44; ++y)
        if (object_pixel(&s.rgb[static_cast<size_t>(3 * (y * s.width + x))])) {
          if (top < 0) top = y;
          bottom = y;
        }
      if (top >= 0) tallest = std::max(tallest, bottom - top + 1);
    }
    // 2 cm; a perspective camera sees a ball of radius R from d a little larger,
    // 2R / sqrt(1 - (R/d)²): under 3 % here
    EXPECT_NEAR(tallest / px_per_cm, 2.0, 0.1) << tallest << " px at " << px_per_cm << " px/cm";
    EXPECT_NEAR(drawn_bar(s), cm * px_per_cm, 2.5) << "the bar drawn is not as long as it says";
    if (px_per_cm_at_1 == 0)
      px_per_cm_at_1 = px_per_cm;
    else
      EXPECT_NEAR(px_per_cm / px_per_cm_at_1, 2.0, 0.05) << "twice as close: twice the scale";
  }
}

}  // namespace
}  // namespace knit
