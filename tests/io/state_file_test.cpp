#include "knit/io/state_file.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <utility>
#include <vector>

#include "fd_check.hpp"
#include "knit/recipes/relax_knit.hpp"

namespace knit {
namespace {

StateFile sample() {
  ModelBuilder b;
  Eigen::Matrix3Xd cp = Eigen::Matrix3Xd::Random(3, 7);
  b.add_yarn(cp);
  b.add_yarn(cp.colwise() + Eigen::Vector3d(0, 3, 0));
  std::vector<StitchCoord> st(8);
  for (int i = 0; i < 8; ++i) st[i] = {i / 3, i % 3};
  b.set_stitches(st);
  const Model m = b.build(Params{});
  State s;
  s.q = b.positions();
  s.v = test::jitter(Eigen::VectorXd::Zero(s.q.size()), 1.0, 4);
  s.time = 0.123456789012345678;
  return make_state_file(m, s);
}

TEST(StateFile, RoundTripsExactly) {
  const std::string path = ::testing::TempDir() + "/round.kstate";
  const StateFile f = sample();
  write_state_file(path, f);
  const StateFile g = read_state_file(path);
  EXPECT_EQ(g.state.q, f.state.q);  // bit-exact
  EXPECT_EQ(g.state.v, f.state.v);
  EXPECT_EQ(g.state.time, f.state.time);
  EXPECT_EQ(g.yarn_cp_counts, f.yarn_cp_counts);
  EXPECT_EQ(g.yarn_radius, f.yarn_radius);
  ASSERT_EQ(g.stitch.size(), f.stitch.size());
  for (size_t i = 0; i < g.stitch.size(); ++i) {
    EXPECT_EQ(g.stitch[i].row, f.stitch[i].row);
    EXPECT_EQ(g.stitch[i].col, f.stitch[i].col);
  }
  EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
}

TEST(StateFile, TruncatedAndCorruptFilesNameTheOffset) {
  const std::string path = ::testing::TempDir() + "/trunc.kstate";
  write_state_file(path, sample());
  const auto size = std::filesystem::file_size(path);
  for (auto cut : {size_t(4), size_t(30), size_t(size / 2), size_t(size - 2)}) {
    std::filesystem::resize_file(path, cut);
    try {
      read_state_file(path);
      FAIL() << "accepted a file cut to " << cut << " bytes";
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find("byte "), std::string::npos) << msg;
    }
    write_state_file(path, sample());
  }
  {
    std::fstream io(path, std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(8);
    const unsigned bad_version = 99;
    io.write(reinterpret_cast<const char*>(&bad_version), 4);
  }
  try {
    read_state_file(path);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("version 99"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_state_file(path + ".missing"), std::runtime_error);
}

// a generated knit's state carries what a later run needs: pattern, size, shrink, rest
// lengths and glues (with their closing gaps)
TEST(StateFile, KnitRoundTrips) {
  const std::string path = ::testing::TempDir() + "/knit.kstate";
  RelaxKnitOptions o;
  o.knit.rows = 4;
  o.knit.cols = 5;
  o.knit.in_the_round = true;
  o.shrink = 0.9;
  const KnitRelaxation r = setup_knit_relaxation("rib2x2", o);
  const Model& m = r.sim->model();
  ASSERT_TRUE(m.knit.has_value());
  write_state_file(path, make_state_file(m, r.state));
  const StateFile g = read_state_file(path);
  ASSERT_TRUE(g.knit.has_value());
  EXPECT_EQ(g.knit->pattern, "rib2x2");
  EXPECT_EQ(g.knit->rows, 4);
  EXPECT_EQ(g.knit->cols, 5);
  EXPECT_TRUE(g.knit->in_the_round);
  EXPECT_EQ(g.knit->segments_per_stitch, 8);
  EXPECT_EQ(g.knit->shrink, 0.9);
  EXPECT_EQ(g.rest_length, m.rest_length);
  ASSERT_EQ(g.glues.size(), m.glues.size());
  ASSERT_FALSE(g.glues.empty());
  for (size_t k = 0; k < g.glues.size(); ++k) {
    EXPECT_EQ(g.glues[k].a.segment, m.glues[k].a.segment);
    EXPECT_EQ(g.glues[k].b.t, m.glues[k].b.t);
    EXPECT_EQ(g.glues[k].gap, m.glues[k].gap);
    EXPECT_EQ(g.glues[k].close_time, m.glues[k].close_time);
  }
  // every truncation is refused with an offset
  const auto size = std::filesystem::file_size(path);
  for (auto cut : {size - 5, size - 40, size - 8 * g.rest_length.size()}) {
    std::filesystem::resize_file(path, cut);
    EXPECT_THROW(read_state_file(path), std::runtime_error) << cut;
    write_state_file(path, make_state_file(m, r.state));
  }
}

// a relaxation's states say how it was relaxing (what `relax --resume` goes on with),
// field for field; a file without that block reads as none, and a hand-edited value out of
// its option's range is refused naming the key
TEST(StateFile, RelaxationSettingsRoundTrip) {
  const std::string path = ::testing::TempDir() + "/relax_settings.kstate";
  RelaxKnitOptions o;
  o.knit.rows = 3;
  o.knit.cols = 3;
  o.fire = true;
  o.params.solver.integrator = Integrator::IMEX_CONTACT;
  o.params.solver.time_step = 6e-4;
  o.params.solver.implicit_bending = true;
  o.params.solver.contact_solve_tolerance = 0.01;
  o.params.solver.contact_reuse = 0.05;
  o.params.solver.max_step_halvings = 3;
  o.params.discretisation.contact_points = 7;
  o.params.discretisation.end_mass_floor = 0.5;
  o.params.material.k_global = 0.4;
  o.params.material.alpha_small = 0.2;
  o.params.material.alpha_large = 0.1;
  o.run.ke_per_length = 3e-6;
  o.run.force_residual = 0.5;
  o.run.check_every = 25;
  o.run.contact_reuse_widen = 2;
  o.run.contact_reuse_widen_residual = 10;
  const KnitRelaxation r = setup_knit_relaxation("garter", o);
  write_state_file(path, make_state_file(r.sim->model(), r.state));
  const StateFile g = read_state_file(path);
  ASSERT_TRUE(g.knit && g.knit->relaxation);
  RelaxKnitOptions back;
  apply_relax_settings(*g.knit->relaxation, back);
  EXPECT_EQ(to_json(relax_settings(back)), to_json(relax_settings(o)));
  EXPECT_TRUE(back.fire);
  EXPECT_EQ(back.params.solver.integrator, Integrator::IMEX_CONTACT);
  EXPECT_EQ(back.params.solver.time_step, 6e-4);
  EXPECT_EQ(back.params.discretisation.contact_points, 7);
  EXPECT_EQ(back.params.material.k_global, 0.4);  // as asked (the FIRE model runs with none)
  EXPECT_EQ(r.sim->model().params.material.k_global, 0.0);
  EXPECT_EQ(back.run.check_every, 25);
  EXPECT_EQ(back.run.contact_reuse_widen_residual, 10.0);
  // a knit written without the block (an earlier build, or by hand)
  StateFile plain = g;
  plain.knit->relaxation.reset();
  write_state_file(path, plain);
  EXPECT_FALSE(read_state_file(path).knit->relaxation.has_value());
  // out of range, of the wrong type, or missing: refused naming the key and the file
  auto refused = [&](KnitRelaxSettings bad, const std::string& key) {
    StateFile f = g;
    f.knit->relaxation = bad;
    write_state_file(path, f);
    try {
      read_state_file(path);
      ADD_FAILURE() << "accepted a bad " << key;
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find("relaxation." + key), std::string::npos) << msg;
    }
  };
  using Spoil = void (*)(KnitRelaxSettings&);
  const std::vector<std::pair<Spoil, std::string>> spoiled = {
      {[](KnitRelaxSettings& b) { b.params.solver.time_step = -1; }, "time_step"},
      {[](KnitRelaxSettings& b) {
         b.params.solver.time_step = std::numeric_limits<double>::quiet_NaN();
       },
       "time_step"},
      {[](KnitRelaxSettings& b) { b.check_every = 0; }, "check_every"},
      {[](KnitRelaxSettings& b) { b.contact_reuse_widen = 0.5; }, "contact_reuse_widen"},
      {[](KnitRelaxSettings& b) { b.params.discretisation.contact_points = 65; }, "contact_points"},
      {[](KnitRelaxSettings& b) { b.params.material.alpha_small = 2; }, "alpha_small"}};
  for (const auto& [spoil, key] : spoiled) {
    KnitRelaxSettings bad = *g.knit->relaxation;
    spoil(bad);
    refused(bad, key);
  }
}

// a run's totals (what a resumed run goes on adding up) round-trip field for field, the
// extremes not reached yet included; a file without them is written as version 3, which
// earlier builds read; a bad field is refused naming it
TEST(StateFile, RunTotalsRoundTrip) {
  const std::string path = ::testing::TempDir() + "/run_totals.kstate";
  auto version = [&] {
    std::ifstream in(path, std::ios::binary);
    in.seekg(8);
    uint32_t v = 0;
    in.read(reinterpret_cast<char*>(&v), 4);
    return v;
  };
  StateFile f = sample();
  write_state_file(path, f);
  EXPECT_EQ(version(), 3u);
  EXPECT_FALSE(read_state_file(path).run.has_value());
  RunTotals t;
  EXPECT_EQ(to_json(t)["min_contact_distance"], nullptr);  // none yet: +infinity
  write_state_file(path, [&] {
    StateFile g = f;
    g.run = t;
    return g;
  }());
  EXPECT_EQ(version(), 4u);
  EXPECT_EQ(to_json(*read_state_file(path).run), to_json(t));
  EXPECT_TRUE(std::isinf(read_state_file(path).run->min_contact_distance));
  t.start_time = 0.1;
  t.end_time = 0.30000000000000004;
  t.steps = 1234;
  t.shortened_steps = {0.7e-4, 0.7e-4};
  t.frames_written = 13;
  t.contact_steps = 1200;
  t.contact_pairs_sum = 123456.5;
  t.min_contact_distance = 0.7601234567890123;
  t.contact_linearised = 7;
  t.matrix_kept = 9;
  t.reuse_scale_sum = 1234.0000000000002;
  t.solve_steps = 5;
  t.solve_iterations = 55;
  t.solve_iterations_max = 17;
  t.solve_residual_max = 1e-7 / 3;
  t.friction_steps = 3;
  t.friction_pairs = 44;
  t.friction_stuck = 40;
  t.friction_passes = 12;
  t.friction_passes_max = 5;
  t.friction_work = 2.0 / 3;
  t.halving = {2, 1300, 3, 1, 11};
  t.warnings = {{"yarns came closer than half the contact distance", 4}};
  t.objects = {{"ball", {0.0123, 456.25}}, {"floor", {0, 0}}};
  f.run = t;
  write_state_file(path, f);
  const StateFile g = read_state_file(path);
  ASSERT_TRUE(g.run.has_value());
  EXPECT_EQ(to_json(*g.run), to_json(t));
  EXPECT_EQ(g.run->min_contact_distance, t.min_contact_distance);  // bit for bit
  EXPECT_EQ(g.run->reuse_scale_sum, t.reuse_scale_sum);
  EXPECT_EQ(g.run->halving.calm, 11);
  EXPECT_EQ(g.run->objects.at("ball").contact_points_sum, 456.25);
  EXPECT_EQ(g.state.q, f.state.q);
  // fields missing, of the wrong type or out of range
  auto refused = [](nlohmann::json j, const std::string& key) {
    try {
      run_totals_from_json(j);
      ADD_FAILURE() << "accepted a bad " << key << ": " << j.dump();
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("run." + key), std::string::npos) << e.what();
    }
  };
  const nlohmann::json good = to_json(t);
  nlohmann::json bad = good;
  bad.erase("steps");
  refused(bad, "steps");
  bad = good;
  bad["steps"] = -1;
  refused(bad, "steps");
  bad = good;
  bad["contact_pairs_sum"] = nullptr;  // only the closest approach may be unset
  refused(bad, "contact_pairs_sum");
  bad = good;
  bad["objects"]["ball"]["deepest_penetration_cm"] = "deep";
  refused(bad, "objects[\"ball\"].deepest_penetration_cm");
  bad = good;
  bad["halving_level"] = 1e10;
  refused(bad, "halving_level");
}

// files written before the knit block existed (version 1) are still read
TEST(StateFile, ReadsVersionOne) {
  for (const char* name : {"helix.kstate", "two-helices.kstate"}) {
    const StateFile f =
        read_state_file(std::string(KNIT_TEST_DATA) + "/../../fuzz/seeds/kstate/" + name);
    EXPECT_FALSE(f.knit.has_value()) << name;
    EXPECT_GT(f.num_cp(), 0) << name;
  }
  const StateFile ref =
      read_state_file(std::string(KNIT_TEST_DATA) + "/reference/relax_stockinette_6x6.kstate");
  EXPECT_FALSE(ref.knit.has_value());
  EXPECT_FALSE(ref.stitch.empty());
}

}  // namespace
}  // namespace knit
