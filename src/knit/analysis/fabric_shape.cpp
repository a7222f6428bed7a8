#include "knit/analysis/fabric_shape.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <limits>
#include <stdexcept>
#include <vector>

namespace knit {

FabricShape measure_fabric(const Model& model, const Eigen::VectorXd& q) {
  FabricShape s;
  for (const StitchCoord& c : model.stitch) {
    s.rows = std::max(s.rows, c.row + 1);
    s.cols = std::max(s.cols, c.col + 1);
  }
  if (s.rows < 2 || s.cols < 2)
    throw std::invalid_argument(
        "measure_fabric: the model needs stitch coordinates with at least 2 rows and 2 columns");
  const int R = s.rows, C = s.cols;
  // stitch centroids from 4 samples per segment (both ends included)
  std::vector<Eigen::Vector3d> sum(R * C, Eigen::Vector3d::Zero());
  std::vector<int> count(R * C, 0);
  std::vector<Eigen::Vector3d> samples;
  std::vector<int> sample_stitch;
  constexpr int PER = 4;
  for (int i = 0; i < model.num_seg(); ++i) {
    const Vector12d x = gather_segment(q, model.seg_cp[i]);
    const StitchCoord st = model.stitch[i];
    for (int k = 0; k < PER; ++k) {
      const Eigen::Vector3d p = combine(x, bspline_basis(static_cast<double>(k) / (PER - 1)));
      samples.push_back(p);
      sample_stitch.push_back(st.row >= 0 ? st.row * C + st.col : -1);
      if (st.row >= 0) {
        sum[st.row * C + st.col] += p;
        ++count[st.row * C + st.col];
      }
    }
  }
  auto has = [&](int r, int c) {
    return r >= 0 && r < R && c >= 0 && c < C && count[r * C + c] > 0;
  };
  auto centroid = [&](int r, int c) -> Eigen::Vector3d {
    return sum[r * C + c] / count[r * C + c];
  };
  const int r0 = R / 4, r1 = std::max(r0 + 1, R - R / 4 - 1);
  const int c0 = C / 4, c1 = std::max(c0 + 1, C - C / 4 - 1);
  auto central = [&](int r, int c) { return r >= r0 && r <= r1 && c >= c0 && c <= c1; };

  // best-fit plane of the central centroids
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  int n = 0;
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c)
      if (has(r, c)) {
        mean += centroid(r, c);
        ++n;
      }
  if (n < 3) throw std::invalid_argument("measure_fabric: too few stitches in the central half");
  mean /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  Eigen::Vector3d course = Eigen::Vector3d::Zero(), wale = Eigen::Vector3d::Zero();
  double sw = 0, rh = 0;
  int nsw = 0, nrh = 0;
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      if (!has(r, c)) continue;
      const Eigen::Vector3d d = centroid(r, c) - mean;
      cov += d * d.transpose();
      if (has(r, c + 1) && c + 1 <= c1) course += centroid(r, c + 1) - centroid(r, c);
      if (has(r + 1, c) && r + 1 <= r1) wale += centroid(r + 1, c) - centroid(r, c);
    }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  course -= course.dot(normal) * normal;
  course.normalize();
  wale -= wale.dot(normal) * normal + wale.dot(course) * course;
  wale.normalize();
  normal = course.cross(wale);
  s.course_axis = course;
  s.wale_axis = wale;
  s.normal = normal;
  // The gauge: distance between stitch centres GAUGE_SPAN columns (rows) apart, per
  // stitch. The span covers a whole 2×2 rib repeat, so ribs that pleat measure drawn in,
  // and is short enough to follow a sheet that rolls.
  const int span_c = std::min(GAUGE_SPAN, c1 - c0), span_r = std::min(GAUGE_SPAN, r1 - r0);
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      if (!has(r, c)) continue;
      if (c + span_c <= c1 && has(r, c + span_c)) {
        sw += (centroid(r, c + span_c) - centroid(r, c)).norm() / span_c;
        ++nsw;
      }
      if (r + span_r <= r1 && has(r + span_r, c)) {
        rh += (centroid(r + span_r, c) - centroid(r, c)).norm() / span_r;
        ++nrh;
      }
    }
  s.stitch_width_cm = nsw ? sw / nsw : 0;
  s.row_height_cm = nrh ? rh / nrh : 0;

  // the piece's size measured along the fabric at the same span (a tape measure laid over
  // a rolled edge), over the central rows (columns), plus half a stitch at either end
  auto along = [&](bool course_dir, int line, int span) {
    const int n = course_dir ? C : R;
    double len = 0;
    int prev = 0;
    for (int k = span; prev < n - 1; k += span) {
      const int next = std::min(k, n - 1);
      const int ra = course_dir ? line : prev, ca = course_dir ? prev : line;
      const int rb = course_dir ? line : next, cb = course_dir ? next : line;
      if (!has(ra, ca) || !has(rb, cb)) return -1.0;
      len += (centroid(rb, cb) - centroid(ra, ca)).norm();
      prev = next;
    }
    return len;
  };
  auto mean_along = [&](bool course_dir) {
    double acc = 0;
    int m = 0;
    for (int line = course_dir ? r0 : c0; line <= (course_dir ? r1 : c1); ++line) {
      const double len = along(course_dir, line, course_dir ? span_c : span_r);
      if (len < 0) continue;
      acc += len;
      ++m;
    }
    return m ? acc / m : 0.0;
  };
  s.course_length_cm = mean_along(true) + s.stitch_width_cm;
  s.wale_length_cm = mean_along(false) + s.row_height_cm;

  double cmin = std::numeric_limits<double>::infinity(), cmax = -cmin, wmin = cmin, wmax = -cmin,
         nmin = cmin, nmax = -cmin;
  for (size_t k = 0; k < samples.size(); ++k) {
    const Eigen::Vector3d d = samples[k] - mean;
    cmin = std::min(cmin, d.dot(course));
    cmax = std::max(cmax, d.dot(course));
    wmin = std::min(wmin, d.dot(wale));
    wmax = std::max(wmax, d.dot(wale));
    const int st = sample_stitch[k];
    if (st >= 0 && central(st / C, st % C)) {
      nmin = std::min(nmin, d.dot(normal));
      nmax = std::max(nmax, d.dot(normal));
    }
  }
  s.course_extent_cm = cmax - cmin;
  s.wale_extent_cm = wmax - wmin;
  s.thickness_cm = (nmax - nmin) + 2 * model.params.material.radius;
  s.loop_length_cm = model.total_length() / (static_cast<double>(R) * C);

  // edges: mean signed offset of their centroids from the central plane
  auto edge_offset = [&](bool by_col, int index) {
    double acc = 0;
    int m = 0;
    for (int j = 0; j < (by_col ? R : C); ++j) {
      const int r = by_col ? j : index, c = by_col ? index : j;
      if (!has(r, c)) continue;
      acc += (centroid(r, c) - mean).dot(normal);
      ++m;
    }
    return m ? acc / m : 0.0;
  };
  s.edge_offset_cm[0] = edge_offset(true, 0);
  s.edge_offset_cm[1] = edge_offset(true, C - 1);
  s.edge_offset_cm[2] = edge_offset(false, 0);
  s.edge_offset_cm[3] = edge_offset(false, R - 1);
  double curl = 0;
  for (double e : s.edge_offset_cm) curl += std::abs(e);
  s.edge_curl = s.stitch_width_cm > 0 ? curl / 4 / s.stitch_width_cm : 0;
  return s;
}

nlohmann::json to_json(const FabricShape& s) {
  return {{"course_extent_cm", s.course_extent_cm},
          {"wale_extent_cm", s.wale_extent_cm},
          {"course_length_cm", s.course_length_cm},
          {"wale_length_cm", s.wale_length_cm},
          {"thickness_cm", s.thickness_cm},
          {"stitch_width_cm", s.stitch_width_cm},
          {"row_height_cm", s.row_height_cm},
          {"loop_length_cm", s.loop_length_cm},
          {"edge_curl", s.edge_curl},
          {"edge_offset_cm",
           {{"left", s.edge_offset_cm[0]},
            {"right", s.edge_offset_cm[1]},
            {"bottom", s.edge_offset_cm[2]},
            {"top", s.edge_offset_cm[3]}}}};
}

}  // namespace knit
