// The elastic sheet beside the knit (recipes/sheet_stretch.hpp): it carries the knit
// exactly when undeformed, its quasi-static stretch test matches the closed form of a
// strip without Poisson coupling, and its stiffnesses fit the yarn model's runs.
#include "knit/recipes/sheet_stretch.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <map>

#include "knit/io/state_file.hpp"
#include "knit/run/interrupt.hpp"
#include "knit/sheet/embedding.hpp"
#include "knit/sheet/sheet_solver.hpp"
#include "recipes/relaxed_sample.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

// a 6×7 stockinette relaxed for 0.1 s by `knitsim relax` (shipped)
std::string relaxed_sample() {
  static const std::string path = relaxed_stockinette_sample(6, 7);
  return path;
}

TEST(SheetStretch, TheUndeformedSheetCarriesTheKnitExactly) {
  StretchOptions o;
  const StretchGeometry g = stretch_geometry(relaxed_sample(), o);
  const KnitSheet ks = make_knit_sheet(g, 0.4);
  // the sheet spans the knit: course along the pull, wale across, in the fabric's plane
  EXPECT_GT(ks.u_axis.dot(g.axis), 0.99);
  EXPECT_LT(std::abs(ks.normal.dot(g.normal)), 1.0 + 1e-12);
  EXPECT_GT(std::abs(ks.normal.dot(g.normal)), 0.999);
  const sheet::SheetEmbedding emb = sheet::embed_points(ks.mesh, ks.embedded);
  const Eigen::Matrix3Xd back = sheet::deform(ks.mesh, emb, ks.mesh.rest_positions());
  EXPECT_LT((back - ks.embedded).cwiseAbs().maxCoeff(), 1e-10);
  // the clamps hold the nodes under the clamped columns: the first and last ones
  EXPECT_EQ(ks.fixed_nodes.size() % ks.mesh.nv, 0u);
  EXPECT_EQ(ks.moving_nodes.size() % ks.mesh.nv, 0u);
  EXPECT_GE(ks.fixed_nodes.size(), static_cast<size_t>(ks.mesh.nv));
}

// A strip whose ends are held rigidly: with no Poisson coupling the free part stretches
// uniformly, so the clamp force is k_u · H · ΔL / L_free (H the strip's extent across the
// pull, L_free the length between the clamped node columns) — linear in the strain, equal
// and opposite at the two clamps.
TEST(SheetStretch, AStripPulledAlongTheCourseMatchesItsClosedForm) {
  SheetStretchOptions o;
  o.stretch.to_strain = 0.2;
  o.stretch.output_strain = 0.05;
  o.stretch.progress = false;
  o.material.k_stretch_u = 2000;
  o.material.k_stretch_v = 3000;
  o.material.k_shear = 500;
  o.material.k_bend = 0.01;
  o.node_spacing = 0.4;
  const StretchResult r = stretch_sheet(relaxed_sample(), o);
  ASSERT_EQ(r.report.summary["status"], "ok") << r.report.summary.dump(2);
  ASSERT_EQ(r.curve.size(), 5u);
  const StretchGeometry g = stretch_geometry(relaxed_sample(), o.stretch);
  const KnitSheet ks = make_knit_sheet(g, o.node_spacing);
  const Eigen::VectorXd rest = ks.mesh.rest_positions();
  double u_fixed = -1e9, u_moving = 1e9;
  for (int n : ks.fixed_nodes) u_fixed = std::max(u_fixed, rest.segment<3>(3 * n).dot(ks.u_axis));
  for (int n : ks.moving_nodes)
    u_moving = std::min(u_moving, rest.segment<3>(3 * n).dot(ks.u_axis));
  const double free_length = u_moving - u_fixed;
  for (const StretchSample& s : r.curve) {
    if (s.strain == 0) continue;
    const double expected = o.material.k_stretch_u * ks.height * s.strain * g.separation /
                            free_length * ks.u_axis.dot(g.axis);
    EXPECT_NEAR(s.force_moving, expected, 0.01 * expected) << "strain " << s.strain;
    EXPECT_NEAR(s.force_fixed, s.force_moving, 1e-6 * s.force_moving);
    // no Poisson coupling: the width does not shrink as the pull grows (the band the width
    // is measured in moves with the middle, so strain 0 samples other yarn points)
    EXPECT_NEAR(s.width, r.curve[1].width, 1e-3 * r.curve[1].width);
  }
}

TEST(SheetStretch, ItsStiffnessesFitTheYarnModelsRuns) {
  // stand-ins for yarn runs: summaries with a small-strain stiffness per direction
  const fs::path root = fs::path(::testing::TempDir()) / "sheet_fit_runs";
  fs::remove_all(root);
  const std::map<std::string, double> stiffness = {
      {"course", 8000}, {"wale", 15000}, {"bias", 5000}};
  std::vector<std::string> runs;
  for (const auto& [d, k] : stiffness) {
    fs::create_directories(root / d);
    std::ofstream(root / d / "summary.json")
        << nlohmann::json({{"model", "yarn"},
                           {"direction", d},
                           {"to_strain", 0.2},
                           {"clamp_stitches", 2},
                           {"stretch", {{"stiffness_small_strain", k}}}})
               .dump();
    runs.push_back((root / d).string());
  }
  SheetStretchOptions base;
  base.node_spacing = 0.5;
  const SheetFit fit = fit_sheet_material(relaxed_sample(), runs, base);
  for (const auto& [d, k] : stiffness) {
    SCOPED_TRACE(d);
    ASSERT_TRUE(fit.report.contains(d)) << fit.report.dump(2);
    EXPECT_NEAR(fit.report[d]["sheet_stiffness"].get<double>(), k, 2e-3 * k);
  }
  // the shear bracket searches from shear as stiff as stretch: a bias target that needs
  // stiffer shear than that and one that needs a hundredth of it are fitted too
  for (double bias : {7500.0, 1000.0}) {
    SCOPED_TRACE(bias);
    std::ofstream(root / "bias" / "summary.json")
        << nlohmann::json({{"model", "yarn"},
                           {"direction", "bias"},
                           {"to_strain", 0.2},
                           {"clamp_stitches", 2},
                           {"stretch", {{"stiffness_small_strain", bias}}}})
               .dump();
    const SheetFit f = fit_sheet_material(relaxed_sample(), runs, base);
    EXPECT_NEAR(f.report["bias"]["sheet_stiffness"].get<double>(), bias, 2e-3 * bias);
    const double k_stretch = std::max(f.material.k_stretch_u, f.material.k_stretch_v);
    if (bias > 5000)
      EXPECT_GT(f.material.k_shear, k_stretch);
    else
      EXPECT_LT(f.material.k_shear, k_stretch / 10);
  }
  // a sheet run with the fitted material has the yarn model's small-strain stiffness
  SheetStretchOptions o = base;
  o.material = fit.material;
  o.stretch.direction = StretchDirection::WALE;
  o.stretch.to_strain = 0.02;
  o.stretch.output_strain = 0.01;
  o.stretch.progress = false;
  const StretchResult r = stretch_sheet(relaxed_sample(), o);
  EXPECT_NEAR(r.curve[1].force_moving / r.curve[1].strain, 15000, 0.02 * 15000);
  // a sheet run or a run that is not a stretch run cannot be fitted to
  fs::create_directories(root / "bad");
  std::ofstream(root / "bad" / "summary.json") << "{\"status\": \"ok\"}";
  EXPECT_THROW(fit_sheet_material(relaxed_sample(), {(root / "bad").string()}, base),
               std::invalid_argument);
  // a signal stops a fit before it writes anything, and a sheet pull after its sample,
  // with what it has and the status "interrupted"
  {
    InterruptHandler handler;
    request_interrupt(SIGINT);
    try {
      fit_sheet_material(relaxed_sample(), runs, base);
      ADD_FAILURE() << "the fit went on after SIGINT";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("interrupted"), std::string::npos) << e.what();
    }
    o.stretch.out_dir = (root / "stopped").string();
    o.stretch.render = false;
    const StretchResult stopped = stretch_sheet(relaxed_sample(), o);
    clear_interrupt();
    EXPECT_EQ(stopped.report.status, StepStatus::INTERRUPTED);
    EXPECT_EQ(stopped.curve.size(), 1u);
    std::ifstream in(root / "stopped" / "summary.json");
    EXPECT_EQ(nlohmann::json::parse(in)["status"], "interrupted");
  }
}

TEST(SheetStretch, BadOptionsAreRefusedBeforeAnythingIsWritten) {
  const std::string out = (fs::path(::testing::TempDir()) / "sheet_bad").string();
  fs::remove_all(out);
  auto message = [&](SheetStretchOptions o) {
    o.stretch.out_dir = out;
    o.stretch.progress = false;
    try {
      stretch_sheet(relaxed_sample(), o);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  SheetStretchOptions soft;
  soft.material.k_shear = -1;
  EXPECT_NE(message(soft).find("k_shear"), std::string::npos) << message(soft);
  SheetStretchOptions coarse;
  coarse.node_spacing = 0;
  EXPECT_NE(message(coarse).find("spacing"), std::string::npos) << message(coarse);
  SheetStretchOptions far;
  far.stretch.to_strain = -0.5;
  EXPECT_NE(message(far).find("--to"), std::string::npos) << message(far);
  EXPECT_FALSE(fs::exists(out)) << "a refused sheet stretch wrote its directory";
}

}  // namespace
}  // namespace knit
