#include "knit/present/plot.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "io/test_states.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

bool is_png(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  return std::string(sig + 1, 3) == "PNG";
}

TEST(PlotCsv, LabelsCarryUnits) {
  EXPECT_EQ(axis_label("displacement_cm"), "displacement (cm)");
  EXPECT_EQ(axis_label("force_dyn"), "force (dyn)");
  EXPECT_EQ(axis_label("kinetic_energy"), "kinetic energy");
  EXPECT_EQ(axis_label("time_s"), "time (s)");
}

TEST(PlotCsv, MalformedLinesAreNamed) {
  const auto dir = test::temp_dir("plot-bad");
  std::ofstream(dir / "a.csv") << "x_cm,y_dyn\n1,2\n3,oops\n";
  try {
    read_csv((dir / "a.csv").string());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("a.csv: line 3: column 'y_dyn': 'oops'"),
              std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "b.csv") << "x_cm,y_dyn\n1,2,3\n";
  EXPECT_THROW(read_csv((dir / "b.csv").string()), std::runtime_error);
  std::ofstream(dir / "log.csv") << "time_s,kinetic_energy\n0,1\n";
  try {
    plot_log(dir.string());
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing column 'potential_energy'"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

TEST(PlotLog, WritesLabelledPlots) {
  if (find_gnuplot().empty()) GTEST_SKIP() << "gnuplot is not installed";
  const auto dir = test::temp_dir("plot-log");
  {
    std::ofstream csv(dir / "log.csv");
    csv << "time_s,kinetic_energy,potential_energy,max_violation,contact_pairs,"
           "min_contact_distance,wall_s_per_step\n";
    for (int k = 0; k < 50; ++k)
      csv << k * 0.01 << "," << 100.0 / (1 + k) << "," << 50 + k << "," << 1e-7 * (1 + k % 5) << ","
          << 1000 + 3 * k << "," << 0.24 + 0.0001 * k << "," << 0.02 << "\n";
  }
  const auto written = plot_log(dir.string());
  ASSERT_EQ(written.size(), 4u);
  for (const char* name : {"energy.png", "constraints.png", "contact.png", "timing.png"}) {
    EXPECT_TRUE(is_png(dir / name)) << name;
    EXPECT_FALSE(fs::exists(dir / (std::string(name) + ".tmp"))) << name;
  }
  std::ofstream(dir / "force.csv") << "displacement_cm,force_dyn\n0,0\n0.5,120\n1.0,300\n";
  EXPECT_EQ(plot_csv((dir / "force.csv").string()), (dir / "force.png").string());
  EXPECT_TRUE(is_png(dir / "force.png"));
  fs::remove_all(dir);
}

// a log with a pin's and a clamp's force columns also gets forces.png
TEST(PlotLog, PlotsConstraintForces) {
  if (find_gnuplot().empty()) GTEST_SKIP() << "gnuplot is not installed";
  const auto dir = test::temp_dir("plot-forces");
  {
    std::ofstream csv(dir / "log.csv");
    csv << "time_s,kinetic_energy,potential_energy,max_violation,contact_pairs,"
           "min_contact_distance,wall_s_per_step,energy_gravity,pin0_fx,pin0_fy,pin0_fz,"
           "top_fx,top_fy,top_fz\n";
    for (int k = 0; k < 20; ++k)
      csv << k * 0.01 << ",1,2,1e-7,0,-1,0.01,-3," << k << ",0,50,0,0," << 100 + k << "\n";
  }
  const auto written = plot_log(dir.string());
  ASSERT_EQ(written.size(), 5u);
  EXPECT_TRUE(is_png(dir / "forces.png"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace knit
