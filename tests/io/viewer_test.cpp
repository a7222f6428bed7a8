// The browser viewer: the page carries the frames and three.js, and headless Chromium shows
// yarn in it and a different picture at another frame.
#include "knit/io/viewer.hpp"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#include "io/external_readers.hpp"
#include "io/test_states.hpp"

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

// Headless Chromium's screenshot of `page` opened at `frame` (software WebGL)
Shot screenshot(const std::string& chromium, const std::filesystem::path& dir,
                const std::string& page, int frame) {
  const std::string png = (dir / ("frame" + std::to_string(frame) + ".png")).string();
  std::string messages;
  const int rc = run_process(
      {chromium, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
       "--use-angle=swiftshader", "--window-size=320,240", "--virtual-time-budget=3000",
       "--screenshot=" + png, "file://" + page + "#frame=" + std::to_string(frame)},
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

}  // namespace
}  // namespace knit
