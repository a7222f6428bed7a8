#include "knit/io/state_file.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "fd_check.hpp"

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

}  // namespace
}  // namespace knit
