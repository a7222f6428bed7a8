#include "knit/present/render.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <fstream>
#include <sstream>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

#include "io/test_states.hpp"
#include "knit/io/states.hpp"
#include "knit/present/sequence.hpp"
#include "knit/spline/fit.hpp"
#include "knit/util/process.hpp"

namespace knit {
namespace {

// distance from point p to the ray (origin o, unit direction d), for points ahead of o
double ray_distance(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& p) {
  const double t = (p - o).dot(d);
  if (t < 0) return std::numeric_limits<double>::infinity();
  return (p - o - t * d).norm();
}

RenderOptions tiny(View view = View::FRONT) {
  RenderOptions o;
  o.width = 64;
  o.height = 48;
  o.view = view;
  o.spp = 4;
  o.shadow_rays = 2;
  o.ao_rays = 2;
  return o;
}

TEST(RenderCamera, FramesEveryCornerInside) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -2, 0), Eigen::Vector3d(3, 1, 0.5));
  for (View v : {View::FRONT, View::BACK, View::SIDE, View::ISO}) {
    const Camera cam = frame_camera(box, v, 80, 60);
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d d =
          box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c)) - cam.eye;
      const double depth = d.dot(cam.forward);
      ASSERT_GT(depth, 0);
      EXPECT_LE(std::abs(d.dot(cam.right)) / depth, cam.tan_half_x * (1 + 1e-9));
      EXPECT_LE(std::abs(d.dot(cam.up)) / depth, cam.tan_half_y * (1 + 1e-9));
    }
  }
  // a swatch in the xy plane is seen face on from +z, with +y up
  const Camera front = frame_camera(box, View::FRONT, 80, 60);
  EXPECT_NEAR(front.forward.z(), -1, 1e-12);
  EXPECT_NEAR(front.up.y(), 1, 1e-12);
  EXPECT_THROW(parse_view("top"), std::invalid_argument);
}

TEST(RenderCamera, TheScaleBarSpansItsLengthAtTheFramedDepth) {
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-3, -2, 0), Eigen::Vector3d(4, 1, 0.5));
  for (View v : {View::FRONT, View::ISO, View::SCENE}) {
    const Camera cam = frame_camera(box, v, 640, 480);
    const auto [length, pixels] = scale_bar_length(cam, box.center());
    // a round length: 1, 2 or 5 × 10^k cm, at most a quarter of the image, more than a tenth
    const double decade = std::pow(10.0, std::floor(std::log10(length)));
    const double m = length / decade;
    EXPECT_TRUE(std::abs(m - 1) < 1e-9 || std::abs(m - 2) < 1e-9 || std::abs(m - 5) < 1e-9) << m;
    EXPECT_LE(pixels, 160);
    EXPECT_GT(pixels, 64);
    // project the box centre and a point `length` cm along the image's right direction
    auto column = [&](const Eigen::Vector3d& p) {
      const Eigen::Vector3d d = p - cam.eye;
      return 320 + d.dot(cam.right) / d.dot(cam.forward) / cam.tan_half_x * 320;
    };
    const Eigen::Vector3d c = box.center();
    EXPECT_NEAR(column(c + length * cam.right) - column(c), pixels, 1.0);
  }
}

TEST(RenderHelix, CoversTheProjectedTube) {
  const StateFile s = test::helix_state();
  RenderOptions o = tiny();
  o.backdrop = false;
  const Image im = render_state(s, o);
  ASSERT_EQ(im.width, 64);
  ASSERT_EQ(im.height, 48);
  const Camera cam = frame_camera(state_bounds(s), o.view, o.width, o.height);
  const Eigen::Matrix3Xd line = sample_bspline(yarn_control_points(s)[0], 64);
  // the centreline point nearest the camera is unoccluded: its pixel shows yarn, unlike
  // the background in the corner
  Eigen::Index nearest = 0;
  (line.transpose() * cam.forward).minCoeff(&nearest);
  const Eigen::Vector3d rel = line.col(nearest) - cam.eye;
  const double depth = rel.dot(cam.forward);
  const int px = static_cast<int>((rel.dot(cam.right) / depth / cam.tan_half_x + 1) * 32);
  const int py = static_cast<int>((1 - rel.dot(cam.up) / depth / cam.tan_half_y) * 24);
  ASSERT_TRUE(px >= 0 && px < 64 && py >= 0 && py < 48);
  EXPECT_EQ(im.coverage[py * 64 + px], 1.0f) << "pixel " << px << "," << py;
  EXPECT_GT((im.pixel(px, py) - im.pixel(0, 0)).norm(), 0.1f);
  // slow oracle: a pixel is covered when its centre ray passes within r of the centreline
  int oracle_hits = 0, mismatches = 0;
  double coverage = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const Eigen::Vector3d d = cam.direction(x + 0.5, y + 0.5);
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index k = 0; k < line.cols(); ++k)
        best = std::min(best, ray_distance(cam.eye, d, line.col(k)));
      const bool hit = best <= 0.125;
      const float c = im.coverage[y * 64 + x];
      oracle_hits += hit;
      coverage += c;
      // pixels the oracle is sure about (centre well inside or outside) must agree
      if (best < 0.125 * 0.7 && c < 0.5) ++mismatches;
      if (best > 0.125 * 1.5 && c > 0) ++mismatches;
    }
  const double fraction = coverage / (64 * 48);
  RecordProperty("coverage_fraction", std::to_string(fraction));
  EXPECT_GT(oracle_hits, 64 * 48 / 20);  // the tube is visible at this size
  EXPECT_NEAR(coverage, oracle_hits, 0.15 * oracle_hits);
  EXPECT_LE(mismatches, 2);
}

TEST(RenderHelix, DeterministicAcrossThreadCounts) {
  const StateFile s = test::state_of({test::helix_control_points()}, 0.125, 0, true);
  RenderOptions o = tiny(View::ISO);
  o.color_rows = true;
  const Image many = render_state(s, o);
  Image one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = render_state(s, o);
  }
  EXPECT_EQ(many.rgb, one.rgb);
}

TEST(RenderHelix, AllViewsAndRowColours) {
  const StateFile s = test::state_of({test::helix_control_points()}, 0.125, 0, true);
  for (View v : {View::FRONT, View::BACK, View::SIDE, View::ISO}) {
    RenderOptions o = tiny(v);
    o.color_rows = true;
    const Image im = render_state(s, o);
    double cov = 0;
    for (float c : im.coverage) cov += c;
    EXPECT_GT(cov, 20) << "view " << static_cast<int>(v);
  }
  RenderOptions bad = tiny();
  bad.spp = 0;
  EXPECT_THROW(render_state(s, bad), std::invalid_argument);
}

TEST(RenderImage, ScaleBarAndCaptionAreDrawnInTheCorners) {
  const StateFile s = test::helix_state();
  RenderOptions o = tiny();
  o.width = 480;
  o.height = 360;
  o.spp = 1;
  const Image plain = render_state(s, o);
  o.scale_bar = true;
  o.caption = "t = 0.250 s";
  const Image marked = render_state(s, o);
  // dark ink where the bar and the caption go, nothing else changed
  auto changed = [&](int x0, int x1, int y0, int y1) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) n += (plain.pixel(x, y) - marked.pixel(x, y)).norm() > 0.2f;
    return n;
  };
  EXPECT_GT(changed(240, 480, 300, 360), 50);  // the bar and its length, bottom right
  EXPECT_GT(changed(0, 240, 320, 360), 30);    // the caption, bottom left
  EXPECT_EQ(changed(0, 480, 0, 280), 0);
}

// Labels come from a TrueType font through FreeType: anti-aliased edges, sizes that follow
// the pixel height and the text, and the non-ASCII signs knitsim's captions use.
TEST(RenderImage, LabelsAreAntiAliasedTrueTypeText) {
  ASSERT_FALSE(label_font_path().empty())
      << "no TrueType font: scripts/setup.sh installs Debian's fonts-dejavu-core";
  const Eigen::Vector2i small = text_size("1 cm", 16), big = text_size("1 cm", 32);
  EXPECT_EQ(small.y(), 16);
  EXPECT_EQ(big.y(), 32);
  EXPECT_NEAR(big.x(), 2 * small.x(), 3);
  EXPECT_GT(text_size("stockinette", 16).x(), text_size("rib", 16).x());
  EXPECT_EQ(text_size("a\nb", 16).y(), 32);
  auto drawn = [](const std::string& text) {
    Image im(120, 40, Eigen::Vector3f::Ones());
    draw_text(im, 4, 4, text, 28, Eigen::Vector3f::Zero());
    return im;
  };
  const Image im = drawn("2 mm");
  int ink = 0, grey = 0;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) {
      const float v = im.pixel(x, y).x();
      ink += v < 0.5f;
      grey += v > 0.1f && v < 0.9f;
    }
  EXPECT_GT(ink, 40);
  EXPECT_GT(grey, 10) << "edges are blended, not a bitmap font's hard squares";
  // the micro and times signs are glyphs of their own, not the '?' of a missing one
  auto differs = [&](const Image& a, const Image& b) { return a.rgb != b.rgb; };
  EXPECT_TRUE(differs(drawn("\u00b5s"), drawn("?s")));
  EXPECT_TRUE(differs(drawn("2\u00d72"), drawn("2?2")));
  EXPECT_TRUE(differs(drawn("\u00b5s"), drawn("\u00d7s")));
  // clipped at the image's edges, not written outside it
  Image tiny(8, 8, Eigen::Vector3f::Ones());
  draw_text(tiny, -5, -5, "WWW", 40, Eigen::Vector3f::Zero());
  draw_text(tiny, 6, 6, "WWW", 40, Eigen::Vector3f::Zero());
}

TEST(RenderImage, PngLabelsAndComposition) {
  Image a(40, 30, Eigen::Vector3f(1, 0, 0)), b(50, 30, Eigen::Vector3f(0, 0, 1));
  const Image both = compose_side_by_side({a, b}, {"stockinette", "rib"});
  EXPECT_EQ(both.width, 40 + 4 + 50);
  EXPECT_GT(both.height, 30);
  // the label strip has dark text pixels
  int dark = 0;
  for (int y = 30; y < both.height; ++y)
    for (int x = 0; x < both.width; ++x) dark += both.pixel(x, y).sum() < 1.0f;
  EXPECT_GT(dark, 10);
  const auto dir = test::temp_dir("png");
  const std::string path = (dir / "c.png").string();
  write_png(both, path);
  std::ifstream in(path, std::ios::binary);
  char sig[8];
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace knit

namespace knit {
namespace {

TEST(RenderCli, SequencesAndComparisons) {
  const auto dir = test::temp_dir("render-cli");
  std::filesystem::create_directories(dir / "states");
  for (int f = 0; f < 2; ++f) {
    StateFile s = test::helix_state(0.1 * f);
    s.state.q.array() *= 1 + 0.2 * f;
    write_state_file((dir / "states" / ("s" + std::to_string(f) + ".kstate")).string(), s);
  }
  std::string msg;
  auto run = [&](std::vector<std::string> args) {
    args.insert(args.begin(), KNIT_APP);
    return run_process(args, msg);
  };
  const std::vector<std::string> quick = {"--size",    "64x48", "--spp",         "1",
                                          "--ao-rays", "1",     "--shadow-rays", "1"};
  auto with = [&](std::vector<std::string> args) {
    args.insert(args.end(), quick.begin(), quick.end());
    return args;
  };
  EXPECT_EQ(run(with({"render", (dir / "states" / "s0.kstate").string(), "--out",
                      (dir / "one.png").string(), "--view", "iso"})),
            0)
      << msg;
  EXPECT_TRUE(std::filesystem::exists(dir / "one.png"));
  EXPECT_EQ(run(with({"render", (dir / "states").string(), "--out", (dir / "frames").string()})), 0)
      << msg;
  EXPECT_TRUE(std::filesystem::exists(dir / "frames" / "frame_0000.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "frames" / "frame_0001.png"));
  if (!find_executable("ffmpeg").empty())
    EXPECT_TRUE(std::filesystem::exists(dir / "frames" / "animation.mp4"));
  EXPECT_EQ(run(with({"render", "--compare", (dir / "states" / "s0.kstate").string(),
                      (dir / "states" / "s1.kstate").string(), "--labels", "before,after", "--out",
                      (dir / "cmp.png").string()})),
            0)
      << msg;
  EXPECT_TRUE(std::filesystem::exists(dir / "cmp.png"));
  // a movie at the simulation's real time: 11 states over 0.1 s are 100 per second, so one
  // in two is shown at 50 frames per second
  std::filesystem::create_directories(dir / "fast");
  for (int f = 0; f <= 10; ++f)
    write_state_file((dir / "fast" / ("s" + std::to_string(10 + f) + ".kstate")).string(),
                     test::helix_state(0.01 * f));
  RenderOptions o = tiny();
  std::filesystem::create_directories(dir / "fast_frames");
  std::vector<std::string> files;
  for (int f = 0; f <= 10; ++f)
    files.push_back((dir / "fast" / ("s" + std::to_string(10 + f) + ".kstate")).string());
  const SequenceResult r = render_sequence(files, o, (dir / "fast_frames").string());
  EXPECT_EQ(r.stride, 2);
  EXPECT_EQ(r.frames, 6);
  EXPECT_NEAR(r.fps, 50, 1e-9);
  EXPECT_TRUE(std::filesystem::exists(dir / "fast_frames" / "frame_0005.png"));
  EXPECT_FALSE(std::filesystem::exists(dir / "fast_frames" / "frame_0006.png"));
  EXPECT_EQ(run({"render", (dir / "states" / "s0.kstate").string(), "--out",
                 (dir / "x.png").string(), "--size", "12"}),
            1);
  EXPECT_NE(msg.find("knitsim: error: --size 12"), std::string::npos) << msg;
  std::filesystem::remove_all(dir);
}

// --box: a close-up frames the given box, the same picture the library draws for that frame
// (rendering does not depend on the thread count), not the whole knit; an empty box is refused
TEST(RenderCli, BoxFramesACloseUp) {
  const auto dir = test::temp_dir("render-box");
  std::filesystem::create_directories(dir);
  const StateFile s = test::helix_state();
  write_state_file((dir / "s.kstate").string(), s);
  const Eigen::AlignedBox3d whole = state_bounds(s);
  Eigen::AlignedBox3d half = whole;
  half.max().x() = whole.center().x();
  std::string msg;
  auto run = [&](std::vector<std::string> args) {
    args.insert(args.begin(), KNIT_APP);
    return run_process(args, msg);
  };
  std::ostringstream box;
  box.precision(17);
  box << half.min().x() << ',' << half.min().y() << ',' << half.min().z() << ',' << half.max().x()
      << ',' << half.max().y() << ',' << half.max().z();
  ASSERT_EQ(run({"render", (dir / "s.kstate").string(), "--out", (dir / "box.png").string(),
                 "--size", "64x48", "--spp", "1", "--ao-rays", "1", "--shadow-rays", "1",
                 "--no-scale-bar", "--box", box.str()}),
            0)
      << msg;
  int w = 0, h = 0, channels = 0;
  unsigned char* px = stbi_load((dir / "box.png").c_str(), &w, &h, &channels, 3);
  ASSERT_NE(px, nullptr);
  const std::vector<uint8_t> cli(px, px + 3 * w * h);
  stbi_image_free(px);
  RenderOptions o = tiny();
  o.spp = o.ao_rays = o.shadow_rays = 1;
  o.frame = half;
  EXPECT_EQ(render_state(s, o).rgb, cli);
  o.frame.reset();
  EXPECT_NE(render_state(s, o).rgb, cli);
  // an empty range names the option and the axis, and writes nothing
  EXPECT_EQ(run({"render", (dir / "s.kstate").string(), "--out", (dir / "bad.png").string(),
                 "--box", "0,0,0,1,-1,1"}),
            1);
  EXPECT_NE(msg.find("--box: its y range"), std::string::npos) << msg;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.png"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace knit
