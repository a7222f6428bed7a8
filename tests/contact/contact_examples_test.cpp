// The contact example scenes start free of overlap: every non-neighbouring pair of contact
// points is at d ≥ 1 (checked with the brute-force path). The yarn shapes are read here
// with a minimal reader of the scene format ("points", "line", "polyline"); the scene
// loader itself lives in scene/.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "knit/contact/contact_term.hpp"
#include "knit/spline/fit.hpp"

namespace knit {
namespace {

Eigen::Vector3d vec3(const nlohmann::json& j) {
  return Eigen::Vector3d(j.at(0).get<double>(), j.at(1).get<double>(), j.at(2).get<double>());
}

Eigen::Matrix3Xd points_of(const nlohmann::json& list) {
  Eigen::Matrix3Xd m(3, list.size());
  for (size_t k = 0; k < list.size(); ++k) m.col(k) = vec3(list[k]);
  return m;
}

// control points of one yarn entry
Eigen::Matrix3Xd yarn_control_points(const nlohmann::json& yarn) {
  if (yarn.contains("points")) return points_of(yarn["points"]);
  if (yarn.contains("polyline"))
    return fit_polyline(points_of(yarn["polyline"]), yarn.at("segments").get<int>());
  if (yarn.contains("line")) {
    // evenly spaced collinear control points: the spline runs exactly from `from` to `to`
    const auto& line = yarn["line"];
    const Eigen::Vector3d a = vec3(line.at("from")), b = vec3(line.at("to"));
    const int n = line.at("segments");
    Eigen::Matrix3Xd cp(3, n + 3);
    for (int k = 0; k < n + 3; ++k) cp.col(k) = a + (k - 1.0) / n * (b - a);
    return cp;
  }
  throw std::invalid_argument("this check reads only points, polyline and line yarns");
}

struct Loaded {
  Model model;
  Eigen::VectorXd q;
  nlohmann::json doc;
};

Loaded load(const std::string& name) {
  const std::string path = std::string(KNIT_EXAMPLES) + "/" + name;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  Loaded out;
  out.doc = nlohmann::json::parse(in);
  Params params;
  if (out.doc.contains("params")) {
    const auto& p = out.doc["params"];
    if (p.contains("radius")) params.material.radius = p["radius"];
    if (p.contains("contact_points")) params.discretisation.contact_points = p["contact_points"];
  }
  ModelBuilder builder;
  for (const auto& yarn : out.doc.at("yarns")) builder.add_yarn(yarn_control_points(yarn));
  out.model = builder.build(params);
  out.q = builder.positions();
  return out;
}

// smallest d over all non-neighbouring contact point pairs (plain loops)
double min_distance_ratio(const Model& m, const Eigen::VectorXd& q) {
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m.num_seg(); ++i)
    for (int j = i + 1; j < m.num_seg(); ++j) {
      if (m.neighbours(i, j)) continue;
      const Vector12d xi = gather_segment(q, m.seg_cp[i]), xj = gather_segment(q, m.seg_cp[j]);
      for (int a = 0; a < m.contact_quad.size(); ++a)
        for (int b = 0; b < m.contact_quad.size(); ++b)
          best = std::min(
              best, (combine(xj, m.contact_quad.b[b]) - combine(xi, m.contact_quad.b[a])).norm());
    }
  return best / (2 * m.params.material.radius);
}

class ContactExamples : public ::testing::TestWithParam<std::string> {};

TEST_P(ContactExamples, StartFreeOfOverlapAndUseOnlyKnownKeys) {
  const Loaded s = load(GetParam());
  const std::set<std::string> top = {"params",       "gravity", "time_step", "duration",
                                     "output_every", "yarns",   "pins",      "glue"};
  for (const auto& [key, value] : s.doc.items()) EXPECT_TRUE(top.count(key)) << "key " << key;
  const std::set<std::string> pin_keys = {"yarn",     "at",    "segment", "t",
                                          "velocity", "start", "stop"};
  for (const auto& pin : s.doc.value("pins", nlohmann::json::array())) {
    EXPECT_LT(pin.at("yarn").get<int>(), static_cast<int>(s.model.yarns.size()));
    for (const auto& [key, value] : pin.items())
      EXPECT_TRUE(pin_keys.count(key)) << "pin key " << key;
  }
  EXPECT_LE(s.model.num_seg(), 300);
  ContactTerm brute(s.model, ContactCulling::BRUTE_FORCE);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(s.q.size());
  EXPECT_EQ(brute.add_force(s.model, s.q, Eigen::VectorXd::Zero(s.q.size()), 0.0, f), 0.0);
  EXPECT_EQ(brute.last_stats().point_pairs_in_contact, 0);
  const double d = min_distance_ratio(s.model, s.q);
  EXPECT_GE(d, 1.0) << GetParam() << ": closest non-neighbouring contact points";
  RecordProperty("min_distance_ratio", std::to_string(d));
}

INSTANTIATE_TEST_SUITE_P(Scenes, ContactExamples,
                         ::testing::Values("crossing.json", "drop_on_yarn.json",
                                           "overhand_knot.json"),
                         [](const auto& info) {
                           std::string n = info.param.substr(0, info.param.find('.'));
                           return n;
                         });

TEST(ContactExamples, OverhandKnotStartsLoose) {
  // its strands stay well apart: d ≥ 2 between points more than 5 segments apart along
  // the yarn, so the pull has slack to take up before the knot tightens
  const Loaded s = load("overhand_knot.json");
  double far = std::numeric_limits<double>::infinity();
  const Model& m = s.model;
  for (int i = 0; i < m.num_seg(); ++i)
    for (int j = i + 6; j < m.num_seg(); ++j)
      for (int a = 0; a < m.contact_quad.size(); ++a)
        for (int b = 0; b < m.contact_quad.size(); ++b)
          far = std::min(far, (combine(gather_segment(s.q, m.seg_cp[j]), m.contact_quad.b[b]) -
                               combine(gather_segment(s.q, m.seg_cp[i]), m.contact_quad.b[a]))
                                  .norm());
  EXPECT_GE(far / (2 * m.params.material.radius), 2.0);
}

}  // namespace
}  // namespace knit
