#include "knit/pattern/generator.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include "knit/spline/basis.hpp"
#include "knit/spline/fit.hpp"

namespace knit {

namespace {

constexpr double PI = 3.14159265358979323846;

// The loop model: Keenan Crane's plain-knit curve (t + a sin 2t, h cos t, ·), one loop per
// 2π of t, head at t = 0, sinkers (the arcs joining neighbouring loops) at ±π; a = 3/2,
// h = 4, loops 2π wide, in units where the yarn radius is 4/5. Crane stacks rows h + 1/2
// apart; we use 4.75 (a slightly more open fabric) and a deeper z swing, D = 2.8 instead
// of 2, because with 8 spline segments per stitch the fitted curve strays up to ~0.3 r
// from the model and the extra depth pays for it. With r = 0.125 cm: stitches 0.98 cm
// wide, rows 0.74 cm apart, the yarns that cross 0.44 cm apart in z.
constexpr double LOOP_A = 1.5;         // rounds the loop (a)
constexpr double LOOP_H = 4.0;         // half height of a loop (h)
constexpr double UNIT_RADIUS = 0.8;    // yarn radius in loop units
constexpr double UNIT_WIDTH = 2 * PI;  // stitch width in loop units
constexpr double UNIT_ROW = 4.75;      // row height in loop units
constexpr double UNIT_DEPTH = 2.8;     // z separation D of yarns where they cross
// The z profile. Seen from the front, each half t ∈ [0, π] of a loop crosses the legs of the
// loop above with its head (t ≈ 0.3), the foot of the loop above with its upper leg
// (t ≈ 1.35), the head of the loop below with its lower leg (t ≈ 1.8) and the upper leg of
// the loop below with its foot (t ≈ 2.85). A knit loop is pulled through the loop below from
// back to front: its legs pass in front of the head below, its foot behind the legs below;
// a purl loop the other way round. Both legs of a loop lie at one depth ℓ (a swing between
// t ≈ 1.35 and 1.8 would be too short for 8 segments per stitch to follow), and each
// crossing fixes the other yarn's depth:
//   legs ℓ(r,c),  head(r,c) = ℓ(r+1,c) − σ(r+1,c) D,  foot(r,c) = ℓ(r−1,c) − σ(r,c) D,
// σ = +1 knit, −1 purl (from the front). Where the row above changes between knit and purl
// (ribs, seed, a tube's seam), the sinker between two of its columns crosses from one face
// to the other between the legs of this row's loops: its two ends lie at ℓ(r,c) − σ(r+1,c) D
// and ℓ(r,c+1) − σ(r+1,c+1) D, so ℓ(r,c) = 0.6 σ(r+1,c) D narrows that swing from 2D to
// 0.8D. Otherwise (stockinette, garter) ℓ = 0. Taking the offset from the stitch above, not
// from the stitch itself, matters where a column changes too (seed): from its own stitch
// the swing would widen to 3.2D and the sinker would pass through the legs. Between these
// depths z follows cos²t (Crane's −d cos 2t when head and foot lie at the same depth).
constexpr double LEG_OFFSET = 0.6;  // ℓ / σ(r+1) D where the row above changes kind
constexpr double SINK_BLEND = 0.5;  // half width (in t) of a sinker's change of depth
// segments of the next piece fitted along with each piece (see generate_knit)
constexpr int LOOKAHEAD_SEGMENTS = 3;
// After the fit, contact points closer than SEPARATION_TARGET·2r are pushed apart (see
// separate_close_pairs). A plain loop of the model comes within 0.918·2r of itself (its
// head passes close to its own legs), so a target of 1 would reshape every stitch of the
// fabrics the model lays well; 0.9 leaves those exactly as laid and lifts the places
// where the model overlaps (seed, a tube's seam and ends) to the same standard. Pushes go
// a little beyond the target so that the iterations end.
constexpr double SEPARATION_TARGET = 0.9;
// contact points per segment at which the distances are measured (min_distance's default)
constexpr int CONTACT_POINTS = 10;

double smoother(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (u * (6 * u - 15) + 10);
}

double blend(double a, double b, double u) {
  return a + (b - a) * smoother(u);
}

struct Dims {
  double w, rh, depth;  // cm
  double sx, sy;        // loop units → cm along x and y
};

// depths (cm) of the parts of one stitch's loop, see the z profile above
struct LoopDepths {
  double head = 0, legs = 0, foot = 0;
  double foot_left = 0, foot_right = 0;  // feet of the neighbours the sinkers lead to
};

// z of a stitch at parameter t ∈ [−π, π]: the legs' depth plus the head's and the foot's
// offsets from it, each weighted by cos²t on its half (Crane's −d cos 2t when head and
// foot lie at the same depth)
double profile_z(double t, const LoopDepths& z) {
  const double tau = std::abs(t), c2 = std::cos(tau) * std::cos(tau);
  if (tau <= 0.5 * PI) return z.legs + (z.head - z.legs) * c2;
  // across the boundary between two stitches the foot's depth changes smoothly from this
  // stitch's to the neighbour's over |t| ∈ [π − SINK_BLEND, π + SINK_BLEND]
  const double nb = t > 0 ? z.foot_right : z.foot_left;
  const double foot = blend(z.foot, nb, (tau - (PI - SINK_BLEND)) / (2 * SINK_BLEND));
  return z.legs + (foot - z.legs) * c2;
}

// arclength parameters of a polyline, scaled to [0, segments]
Eigen::VectorXd chord_parameters(const Eigen::Matrix3Xd& p, int segments) {
  Eigen::VectorXd u(p.cols());
  u[0] = 0;
  for (int j = 1; j < p.cols(); ++j) u[j] = u[j - 1] + (p.col(j) - p.col(j - 1)).norm();
  return u * (segments / u[p.cols() - 1]);
}

struct PieceSpec {
  Eigen::Matrix3Xd points;  // dense centreline in yarn order (unrolled coordinates)
  int segments = 0;
  YarnPiece kind = YarnPiece::STITCH;
  StitchCoord first, second;  // stitch of the first and of the second half of the segments
};

class Layout {
 public:
  Layout(const Pattern& pattern, const KnitOptions& opt, const Dims& dims)
      : m_pattern(pattern), m_opt(opt), m_dims(dims) {}

  // +1 knit, −1 purl; rows above the top continue the top row, below row 0 repeat row 0
  int sigma(int row, int col) const {
    row = std::clamp(row, 0, m_opt.rows - 1);
    return m_pattern.is_knit(row, col) ? 1 : -1;
  }
  // whether the sinkers on either side of (row, col) lead to a stitch of the other kind
  bool mixed(int row, int col) const {
    row = std::clamp(row, 0, m_opt.rows - 1);
    for (int dc : {-1, 1}) {
      const auto [nr, nc] = neighbour(row, col, dc);
      if (sigma(nr, nc) != sigma(row, col)) return true;
    }
    return false;
  }
  // depth of the legs of (row, col): offset towards the face the stitch above is pulled
  // through to when that stitch's row changes kind beside it, because the feet of the row
  // above cross these legs (see the z profile)
  double legs(int row, int col) const {
    const int above = std::clamp(row + 1, 0, m_opt.rows - 1);
    if (!mixed(above, col)) return 0.0;
    return LEG_OFFSET * sigma(above, col) * m_dims.depth;
  }
  double head(int row, int col) const {
    return legs(row + 1, col) - sigma(row + 1, col) * m_dims.depth;
  }
  double foot(int row, int col) const {
    return legs(row - 1, col) - sigma(row, col) * m_dims.depth;
  }
  // the stitch the yarn reaches through the sinker at the left (dc = −1) or right (+1)
  // of (row, col), or the stitch itself at the edge of a flat piece
  std::pair<int, int> neighbour(int row, int col, int dc) const {
    const int c = col + dc;
    if (c >= 0 && c < m_opt.cols) return {row, c};
    if (!m_opt.in_the_round) return {row, col};
    // the helix goes on into the rows below the first and above the last (which repeat
    // them), where the tube's ends run on
    return c < 0 ? std::make_pair(row - 1, m_opt.cols - 1) : std::make_pair(row + 1, 0);
  }

  // centre of the loop of (row, col) in unrolled coordinates, and the helix ramp
  double loop_x(int row, int col) const {
    if (m_opt.in_the_round) return (row * m_opt.cols + col) * m_dims.w;
    return (col - 0.5 * (m_opt.cols - 1)) * m_dims.w;
  }
  double row_y(int row) const { return (row - 0.5 * (m_opt.rows - 1)) * m_dims.rh; }

  LoopDepths depths(int row, int col) const {
    LoopDepths z;
    z.head = head(row, col);
    z.legs = legs(row, col);
    z.foot = foot(row, col);
    const auto [lr, lc] = neighbour(row, col, -1);
    const auto [rr, rc] = neighbour(row, col, +1);
    z.foot_left = foot(lr, lc);
    z.foot_right = foot(rr, rc);
    return z;
  }

  // dense stitch curve; `forward` = the yarn runs in +x
  Eigen::Matrix3Xd stitch_points(int row, int col, bool forward, int n) const {
    const LoopDepths z = depths(row, col);
    Eigen::Matrix3Xd p(3, n + 1);
    for (int k = 0; k <= n; ++k) {
      const double t = forward ? -PI + 2 * PI * k / n : PI - 2 * PI * k / n;
      double y = row_y(row) + m_dims.sy * LOOP_H * std::cos(t);
      if (m_opt.in_the_round) y += m_dims.rh * (col + t / (2 * PI)) / m_opt.cols;
      p.col(k) = Eigen::Vector3d(loop_x(row, col) + m_dims.sx * (t + LOOP_A * std::sin(2 * t)), y,
                                 profile_z(t, z));
    }
    return p;
  }

  // the sinker end of a row's edge stitch (t = ±π)
  Eigen::Vector3d edge_point(int row, bool right) const {
    const int col = right ? m_opt.cols - 1 : 0;
    const double t = right ? PI : -PI;
    double y = row_y(row) + m_dims.sy * LOOP_H * std::cos(t);
    if (m_opt.in_the_round) y += m_dims.rh * (col + t / (2 * PI)) / m_opt.cols;
    // the sinker's depth there, halfway between this stitch's foot and the neighbour's
    const auto [nr, nc] = neighbour(row, col, right ? 1 : -1);
    return {loop_x(row, col) + m_dims.sx * t, y, blend(foot(row, col), foot(nr, nc), 0.5)};
  }

  // a flat piece doubles back: a half circle in the fabric plane from the end of `row` to
  // the start of row + 1, outside the edge, its z turning from one sinker's to the other's
  Eigen::Matrix3Xd turn_points(int row, bool right, int n) const {
    const Eigen::Vector3d a = edge_point(row, right), b = edge_point(row + 1, right);
    const double rho = 0.5 * (b.y() - a.y()), side = right ? 1.0 : -1.0;
    Eigen::Matrix3Xd p(3, n + 1);
    for (int k = 0; k <= n; ++k) {
      const double phi = PI * k / n;
      p.col(k) =
          Eigen::Vector3d(a.x() + side * rho * std::sin(phi), a.y() + rho * (1 - std::cos(phi)),
                          blend(a.z(), b.z(), static_cast<double>(k) / n));
    }
    return p;
  }

  // A yarn carried up the edge from the end of `row` to the start of `to` (> row + 1), the
  // rows between knit by other yarns: it curls outside the edge (`reach` cm out, as a free
  // end does) to `z_lane` behind the fabric, runs up behind the edge stitch there (quarter
  // circles of radius rh/2 into and out of the run) and curls back into row `to`.
  Eigen::Matrix3Xd carry_points(int row, int to, bool right, double z_lane, double reach,
                                int n) const {
    const Eigen::Vector3d a = edge_point(row, right), b = edge_point(to, right);
    const double s = right ? 1.0 : -1.0, q = 0.5 * m_dims.rh;
    std::vector<Eigen::Vector3d> pts;
    const int n_curl = std::max(4, n / 4), n_arc = std::max(4, n / 8);
    for (int k = 0; k <= n_curl; ++k) {
      const double phi = PI * k / n_curl;
      pts.emplace_back(a.x() + s * reach * std::sin(phi), a.y(),
                       a.z() - 0.5 * (a.z() - z_lane) * (1 - std::cos(phi)));
    }
    for (int k = 1; k <= n_arc; ++k) {
      const double psi = 0.5 * PI * k / n_arc;
      pts.emplace_back(a.x() - s * q * std::sin(psi), a.y() + q * (1 - std::cos(psi)), z_lane);
    }
    const int n_run = std::max(2, n - 2 * n_curl - 2 * n_arc);
    for (int k = 1; k < n_run; ++k)
      pts.emplace_back(a.x() - s * q, a.y() + q + (b.y() - a.y() - 2 * q) * k / n_run, z_lane);
    for (int k = 0; k < n_arc; ++k) {
      const double psi = 0.5 * PI * k / n_arc;
      pts.emplace_back(b.x() - s * q * std::cos(psi), b.y() - q + q * std::sin(psi), z_lane);
    }
    for (int k = 0; k <= n_curl; ++k) {
      const double phi = PI * k / n_curl;
      pts.emplace_back(b.x() + s * reach * std::sin(phi), b.y(),
                       z_lane + 0.5 * (b.z() - z_lane) * (1 - std::cos(phi)));
    }
    Eigen::Matrix3Xd p(3, pts.size());
    for (size_t k = 0; k < pts.size(); ++k) p.col(k) = pts[k];
    return p;
  }

  // a free end: from the edge point `e` (where the yarn moves along `dir_x` into the
  // fabric) it curls back outside the edge (half an ellipse in the xz plane, `reach` cm out
  // in x) to z_back behind the fabric and runs `run` cm along the back. Returned from the
  // edge outwards.
  Eigen::Matrix3Xd tail_points(const Eigen::Vector3d& e, double dir_x, double z_back, double reach,
                               double run, int n) const {
    const double rz = 0.5 * (e.z() - z_back);
    const int n_arc = n / 2;
    Eigen::Matrix3Xd p(3, n + 1);
    for (int k = 0; k <= n_arc; ++k) {
      const double phi = PI * k / n_arc;
      p.col(k) = Eigen::Vector3d(e.x() - dir_x * reach * std::sin(phi), e.y(),
                                 e.z() - rz * (1 - std::cos(phi)));
    }
    for (int k = n_arc + 1; k <= n; ++k)
      p.col(k) = Eigen::Vector3d(e.x() + dir_x * run * (k - n_arc) / (n - n_arc), e.y(), z_back);
    return p;
  }

  // the free end of a tube: the helix leaves no room to curl back beside the last stitch
  // (the first stitch of the last row lies there), so the yarn runs on `length` cm along
  // the course as the sinkers of a next row would, across the legs of the last row at the
  // depth of that row's feet
  Eigen::Matrix3Xd run_on_points(double length, int n) const {
    const int row = m_opt.rows - 1;
    const Eigen::Vector3d e = edge_point(row, true);
    const double slope = m_dims.rh / (m_opt.cols * m_dims.w);  // the helix's rise
    // half width in x of a sinker's change of depth (see profile_z)
    const double b = m_dims.sx * (SINK_BLEND + LOOP_A * std::sin(2 * SINK_BLEND));
    Eigen::Matrix3Xd p(3, n + 1);
    for (int k = 0; k <= n; ++k) {
      const double s = length * k / n;
      double z = blend(e.z(), foot(row + 1, 0), s / (2 * b));
      for (int j = 1; j * m_dims.w < s + b; ++j)
        z = blend(z, foot(row + 1, j % m_opt.cols), (s - j * m_dims.w + b) / (2 * b));
      p.col(k) = Eigen::Vector3d(e.x() + s, e.y() + slope * s, z);
    }
    return p;
  }

  // the tube's circumference is cols·w at the back of the loops (z = −depth), so the
  // inner layer keeps the flat spacing and the outer one opens up
  double tube_radius() const { return m_opt.cols * m_dims.w / (2 * PI) + m_dims.depth; }

  Eigen::Vector3d wrap(const Eigen::Vector3d& u) const {
    if (!m_opt.in_the_round) return u;
    const double circ = m_opt.cols * m_dims.w;
    const double theta = 2 * PI * u.x() / circ, rr = tube_radius() + u.z();
    return {rr * std::sin(theta), u.y(), rr * std::cos(theta)};
  }

 private:
  const Pattern& m_pattern;
  const KnitOptions& m_opt;
  const Dims& m_dims;
};

double curve_length(const Eigen::Matrix3Xd& p) {
  return polyline_length(p);
}

// yarn length of one plain (stockinette) loop with these dimensions
double plain_loop_length(const Dims& dims) {
  LoopDepths plain;
  plain.head = plain.foot = plain.foot_left = plain.foot_right = -dims.depth;
  const int n = 2000;
  Eigen::Matrix3Xd p(3, n + 1);
  for (int k = 0; k <= n; ++k) {
    const double t = -PI + 2 * PI * k / n;
    p.col(k) = Eigen::Vector3d(dims.sx * (t + LOOP_A * std::sin(2 * t)),
                               dims.sy * LOOP_H * std::cos(t), profile_z(t, plain));
  }
  return curve_length(p);
}

Dims resolve_dims(const KnitOptions& opt) {
  const double unit = opt.radius / UNIT_RADIUS;
  Dims d;
  d.w = opt.stitch_width_cm > 0 ? opt.stitch_width_cm : UNIT_WIDTH * unit;
  d.rh = opt.row_height_cm > 0 ? opt.row_height_cm : UNIT_ROW * unit;
  d.depth = opt.loop_depth_cm > 0 ? opt.loop_depth_cm : UNIT_DEPTH * unit;
  auto set_scale = [&](double f, Dims& x) {
    x.sx = f * d.w / UNIT_WIDTH;
    x.sy = f * d.rh / UNIT_ROW;
    x.w = f * d.w;
    x.rh = f * d.rh;
  };
  set_scale(1.0, d);
  if (opt.stitch_size_cm > 0) {
    // the loop length grows monotonically with the in-plane scale: bisect for it
    Dims probe = d;
    double lo = 1e-3, hi = 1e3;
    for (int it = 0; it < 200; ++it) {
      const double mid = std::sqrt(lo * hi);
      Dims tmp = d;
      set_scale(mid, tmp);
      (plain_loop_length(tmp) < opt.stitch_size_cm ? lo : hi) = mid;
      if (hi / lo < 1 + 1e-12) break;
    }
    set_scale(std::sqrt(lo * hi), probe);
    d = probe;
  }
  return d;
}

// The rows one yarn knits, in order, and the direction of each (a flat piece's rows run
// forward, in +x, or back).
struct YarnRows {
  std::vector<int> rows;
  std::vector<char> forward;  // per entry of rows
};

// z behind the fabric where the free ends of `row` run: one yarn diameter (and a little)
// behind the back of the row's legs and feet (the ends lie at the height of the sinkers,
// beside the legs and feet; the heads are a row height away); inside a tube, not past its
// axis.
double z_back_of_row(const Layout& layout, const KnitOptions& opt, int row) {
  double z = std::numeric_limits<double>::infinity();
  for (int col = 0; col < opt.cols; ++col)
    z = std::min({z, layout.legs(row, col), layout.foot(row, col)});
  z -= 2.2 * opt.radius;
  if (opt.in_the_round) z = std::max(z, -layout.tube_radius() + 2 * opt.radius);
  return z;
}

// Lays a yarn's free ends: the start tail into pieces[start] (left empty for it) and the end
// tail after its last piece. Returns the segments of each.
int lay_tails(const Layout& layout, const KnitOptions& opt, const Dims& dims, double seg_len,
              const YarnRows& yarn, size_t start, std::vector<PieceSpec>& pieces) {
  // a flat piece's ends curl outside its edge (see tail_points); so does a tube's start,
  // where the stitch beside it, the last of the first round, lies a row height up (a
  // tube's end runs on instead, see run_on_points). Inside a narrow tube the
  // tail's run along the back bends around the axis more tightly than its few segments
  // can follow, so there it goes at most an eighth of the way around.
  double tail_run = 0.75 * dims.w;
  if (opt.in_the_round) tail_run = std::min(tail_run, opt.cols * dims.w / 8);
  const double tail_reach = 0.35 * dims.w;
  const double tail_len = tail_run + PI * std::max(tail_reach, dims.depth + 1.1 * opt.radius);
  int k_tail = std::max(3, static_cast<int>(std::lround(tail_len / seg_len)));

  // the free ends run behind the back of the first and last rows and curl around the edge
  // into the first and out of the last stitch
  {
    const int row = yarn.rows.front();
    const bool forward = yarn.forward.front();
    const int edge = forward ? 0 : opt.cols - 1;
    const Eigen::Vector3d e = layout.edge_point(row, !forward);
    const Eigen::Matrix3Xd out = layout.tail_points(
        e, forward ? 1.0 : -1.0, z_back_of_row(layout, opt, row), tail_reach, tail_run, 8 * k_tail);
    pieces[start] = {out.rowwise().reverse(), k_tail, YarnPiece::TAIL, {row, edge}, {row, edge}};
  }
  if (opt.in_the_round) {
    // inside a tube the tail runs on a smaller circle than the loops: counted from its
    // length as laid, its segments stay about as long as the stitches' (shorter ones are
    // stiffer under the length energy and need a smaller time step)
    Eigen::Matrix3Xd laid = pieces[start].points;
    for (int j = 0; j < laid.cols(); ++j) laid.col(j) = layout.wrap(laid.col(j));
    k_tail = std::max(3, static_cast<int>(std::lround(polyline_length(laid) / seg_len)));
    pieces[start].segments = k_tail;
    pieces.push_back({layout.run_on_points(k_tail * seg_len, 8 * k_tail),
                      k_tail,
                      YarnPiece::TAIL,
                      {opt.rows - 1, opt.cols - 1},
                      {opt.rows - 1, opt.cols - 1}});
  } else {
    const int last = yarn.rows.back();
    const bool forward = yarn.forward.back();
    const int edge = forward ? opt.cols - 1 : 0;
    const Eigen::Vector3d e = layout.edge_point(last, forward);
    pieces.push_back({layout.tail_points(e, forward ? -1.0 : 1.0, z_back_of_row(layout, opt, last),
                                         tail_reach, tail_run, 8 * k_tail),
                      k_tail,
                      YarnPiece::TAIL,
                      {last, edge},
                      {last, edge}});
  }
  return k_tail;
}

void check_options(const Pattern& pattern, const KnitOptions& opt) {
  if (pattern.num_rows() == 0 || pattern.num_cols() == 0)
    throw std::invalid_argument("generate_knit: the pattern is empty");
  if (opt.rows < 1)
    throw std::invalid_argument("knit option rows must be >= 1, got " + std::to_string(opt.rows));
  if (opt.cols < 1)
    throw std::invalid_argument("knit option cols must be >= 1, got " + std::to_string(opt.cols));
  if (opt.in_the_round && opt.cols < 3)
    throw std::invalid_argument("knit option cols must be >= 3 to knit in the round, got " +
                                std::to_string(opt.cols));
  if (opt.segments_per_stitch < 4)
    throw std::invalid_argument("knit option segments_per_stitch must be >= 4, got " +
                                std::to_string(opt.segments_per_stitch));
  if (opt.bind_off && opt.rows < 2)
    throw std::invalid_argument(
        "knit option bind_off needs at least 2 rows (the last row is tied to the one below), "
        "got rows = " +
        std::to_string(opt.rows));
  if (opt.cast_on && opt.rows < 2)
    throw std::invalid_argument(
        "knit option cast_on needs at least 2 rows (the second row is tied to the first), "
        "got rows = " +
        std::to_string(opt.rows));
  if (!pattern.row_yarn.empty()) {
    const int n = pattern.num_rows();
    if (static_cast<int>(pattern.row_yarn.size()) != n ||
        static_cast<int>(pattern.row_leftward.size()) != n)
      throw std::invalid_argument(
          "generate_knit: a pattern of several yarns needs the yarn and the direction of each "
          "of its " +
          std::to_string(n) + " rows");
    std::vector<char> used(n, 0);
    for (int y : pattern.row_yarn) {
      if (y < 0 || y >= n)
        throw std::invalid_argument("generate_knit: a row's yarn is out of range");
      used[y] = 1;
    }
    if (std::find(used.begin(), used.begin() + pattern.num_yarns(), 0) !=
        used.begin() + pattern.num_yarns())
      throw std::invalid_argument("generate_knit: the yarns are not numbered 0, 1, … in order");
    if (opt.in_the_round)
      throw std::invalid_argument(
          "knit option in_the_round: a pattern of several yarns is laid flat (stripes in the "
          "round are not laid yet)");
    if (opt.rows != n)
      throw std::invalid_argument(
          "knit option rows: a pattern of several yarns is laid at its "
          "own " +
          std::to_string(n) + " rows, got " + std::to_string(opt.rows));
  }
  if (!(opt.radius > 0) || !std::isfinite(opt.radius))
    throw std::invalid_argument("knit option radius must be a positive length in cm, got " +
                                std::to_string(opt.radius));
  const std::pair<const char*, double> lengths[] = {{"stitch_size_cm", opt.stitch_size_cm},
                                                    {"stitch_width_cm", opt.stitch_width_cm},
                                                    {"row_height_cm", opt.row_height_cm},
                                                    {"loop_depth_cm", opt.loop_depth_cm}};
  for (const auto& [name, value] : lengths)
    if (!(value >= 0) || !std::isfinite(value))
      throw std::invalid_argument(std::string("knit option ") + name +
                                  " must be a length >= 0 in cm (0 = default), got " +
                                  std::to_string(value));
}

// the first control point of each segment of yarns laid one after the other (yarn y's n_y
// segments have n_y + 3 control points)
std::vector<int> first_control_points(const std::vector<int>& yarn_segments) {
  std::vector<int> first;
  int cp = 0;
  for (int n : yarn_segments) {
    for (int i = 0; i < n; ++i) first.push_back(cp + i);
    cp += n + 3;
  }
  return first;
}

// The two ties of the loop of `top` to the loop of `below` (the stitch under it), for the
// bind-off (`top` in the last row) and the cast-on (`top` in the second row): where its
// legs cross that loop's head, the upper part of the loop below (above
// LEG_CROSSING_HEIGHT of its height), each tie at the closest pair of yarn points there. The two
// legs are told apart by their place along the yarn: the second tie is the closest pair at least a
// quarter of the loop away from the first.
std::vector<Glue> edge_ties(const Eigen::Matrix3Xd& cp, const std::vector<int>& first_cp,
                            const std::vector<StitchCoord>& stitch,
                            const std::vector<YarnPiece>& piece, StitchCoord top,
                            StitchCoord below) {
  constexpr int n = 16;                        // samples per segment
  constexpr double LEG_CROSSING_HEIGHT = 0.8;  // of the loop below, from its bottom
  struct Sample {
    YarnPoint at;
    Eigen::Vector3d x;
    int index;  // along the loop, in samples
  };
  auto samples = [&](StitchCoord s) {
    std::vector<Sample> out;
    for (int i = 0; i < static_cast<int>(stitch.size()); ++i)
      if (piece[i] == YarnPiece::STITCH && stitch[i].row == s.row && stitch[i].col == s.col)
        for (int k = 0; k < n; ++k) {
          const double t = (k + 0.5) / n;
          out.push_back({{i, t}, cp.middleCols<4>(first_cp[i]) * bspline_basis(t), 0});
        }
    for (size_t j = 0; j < out.size(); ++j) out[j].index = static_cast<int>(j);
    return out;
  };
  const std::vector<Sample> a = samples(top), b = samples(below);
  if (a.empty() || b.empty()) return {};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Sample& s : b) lo = std::min(lo, s.x.y()), hi = std::max(hi, s.x.y());
  const double head_from = lo + LEG_CROSSING_HEIGHT * (hi - lo);
  std::vector<Glue> ties;
  int first = -1;
  for (int tie = 0; tie < 2; ++tie) {
    double best = std::numeric_limits<double>::infinity();
    const Sample *sa = nullptr, *sb = nullptr;
    for (const Sample& p : a) {
      if (first >= 0 && std::abs(p.index - first) < static_cast<int>(a.size()) / 4) continue;
      for (const Sample& q : b) {
        if (q.x.y() < head_from) continue;
        const double d = (p.x - q.x).squaredNorm();
        if (d < best) best = d, sa = &p, sb = &q;
      }
    }
    if (!sa) break;
    first = sa->index;
    ties.push_back({sa->at, sb->at});
  }
  return ties;
}

// closest point on the spline to `p` among segments accepted by `allowed`
template <class Allowed>
YarnPoint closest_point(const Eigen::Matrix3Xd& cp, const Eigen::Vector3d& p, Allowed allowed) {
  const int nseg = static_cast<int>(cp.cols()) - 3;
  const int n = 16;
  YarnPoint best;
  double best_d = std::numeric_limits<double>::infinity();
  auto eval = [&](int i, double t) { return (cp.middleCols<4>(i) * bspline_basis(t) - p).norm(); };
  for (int i = 0; i < nseg; ++i) {
    if (!allowed(i)) continue;
    for (int k = 0; k <= n; ++k) {
      const double d = eval(i, static_cast<double>(k) / n);
      if (d < best_d) best_d = d, best = {i, static_cast<double>(k) / n};
    }
  }
  // refine by golden-section search around the best sample
  double lo = std::max(0.0, best.t - 1.0 / n), hi = std::min(1.0, best.t + 1.0 / n);
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  for (int it = 0; it < 60; ++it) {
    const double a = hi - g * (hi - lo), b = lo + g * (hi - lo);
    if (eval(best.segment, a) < eval(best.segment, b))
      hi = b;
    else
      lo = a;
  }
  best.t = 0.5 * (lo + hi);
  return best;
}

}  // namespace

namespace {

// The rows each yarn knits and their directions: one yarn knits every row, to and fro from
// the left (around a tube: always forward), or the pattern's yarns (Pattern::row_yarn).
std::vector<YarnRows> yarn_rows(const Pattern& pattern, const KnitOptions& opt) {
  if (pattern.row_yarn.empty()) {
    YarnRows one;
    for (int row = 0; row < opt.rows; ++row) {
      one.rows.push_back(row);
      one.forward.push_back(opt.in_the_round || row % 2 == 0);
    }
    return {one};
  }
  std::vector<YarnRows> yarns(pattern.num_yarns());
  for (int row = 0; row < opt.rows; ++row) {
    YarnRows& y = yarns[pattern.row_yarn[row]];
    const bool forward = !pattern.row_leftward[row];
    if (!y.rows.empty() && y.forward.back() == forward)
      throw std::invalid_argument("generate_knit: yarn " + std::to_string(pattern.row_yarn[row]) +
                                  " knits rows " + std::to_string(y.rows.back()) + " and " +
                                  std::to_string(row) +
                                  " in the same direction: it would float back along the row");
    y.rows.push_back(row);
    y.forward.push_back(forward);
  }
  return yarns;
}

// Carries up the edges (a yarn's consecutive rows more than one row apart): the lane of
// each, by its yarn and the index of its first row in YarnRows::rows. Carries on one edge
// whose rows overlap run in different lanes (lane 1, 2, …: deeper behind the fabric).
std::map<std::pair<int, int>, int> carry_lanes(const std::vector<YarnRows>& yarns) {
  struct Carry {
    int from, to, yarn, index;
  };
  std::vector<Carry> carries[2];  // by edge: left, right
  for (int y = 0; y < static_cast<int>(yarns.size()); ++y)
    for (size_t j = 0; j + 1 < yarns[y].rows.size(); ++j)
      if (yarns[y].rows[j + 1] > yarns[y].rows[j] + 1)
        carries[yarns[y].forward[j] ? 1 : 0].push_back(
            {yarns[y].rows[j], yarns[y].rows[j + 1], y, static_cast<int>(j)});
  std::map<std::pair<int, int>, int> lane;
  for (auto& edge : carries) {
    std::sort(edge.begin(), edge.end(),
              [](const Carry& a, const Carry& b) { return a.from < b.from; });
    std::vector<std::pair<int, int>> placed;  // (to, lane) of the carries placed
    for (const Carry& c : edge) {
      std::set<int> taken;
      for (const auto& [to, l] : placed)
        if (to > c.from) taken.insert(l);
      int l = 1;
      while (taken.count(l)) ++l;
      placed.push_back({c.to, l});
      lane[{c.yarn, c.index}] = l;
    }
  }
  return lane;
}

// Fits one yarn's pieces with its segments: each piece is fitted together with the first
// segments of the next one, so its last control points (which the next piece holds fixed)
// follow the curve ahead; only the piece's own control points are kept. Appends the
// segments' stitches and pieces.
Eigen::Matrix3Xd fit_pieces(const std::vector<PieceSpec>& pieces, const Layout& layout,
                            std::vector<StitchCoord>& stitch, std::vector<YarnPiece>& kind) {
  int total_seg = 0;
  for (const auto& p : pieces) total_seg += p.segments;
  Eigen::Matrix3Xd out(3, total_seg + 3);
  std::vector<Eigen::Matrix3Xd> wrapped(pieces.size());
  std::vector<Eigen::VectorXd> params(pieces.size());
  for (size_t p = 0; p < pieces.size(); ++p) {
    wrapped[p].resize(3, pieces[p].points.cols());
    for (int j = 0; j < pieces[p].points.cols(); ++j)
      wrapped[p].col(j) = layout.wrap(pieces[p].points.col(j));
    params[p] = chord_parameters(wrapped[p], pieces[p].segments);
  }
  int ncp = 0;
  for (size_t p = 0; p < pieces.size(); ++p) {
    const PieceSpec& piece = pieces[p];
    const int seg = piece.segments;
    int ahead = 0;
    std::vector<int> take;
    if (p + 1 < pieces.size()) {
      ahead = std::min(LOOKAHEAD_SEGMENTS, pieces[p + 1].segments);
      for (int j = 1; j < params[p + 1].size(); ++j)
        if (params[p + 1][j] <= ahead + 1e-12) take.push_back(j);
    }
    const int n_own = static_cast<int>(wrapped[p].cols());
    Eigen::Matrix3Xd pts(3, n_own + take.size());
    Eigen::VectorXd u(n_own + take.size());
    pts.leftCols(n_own) = wrapped[p];
    u.head(n_own) = params[p];
    for (size_t j = 0; j < take.size(); ++j) {
      pts.col(n_own + j) = wrapped[p + 1].col(take[j]);
      u[n_own + j] = seg + params[p + 1][take[j]];
    }
    const Eigen::Matrix3Xd fixed =
        ncp == 0 ? Eigen::Matrix3Xd() : Eigen::Matrix3Xd(out.middleCols(ncp - 3, 3));
    const Eigen::Matrix3Xd cp = fit_bspline(pts, u, seg + ahead, fixed, 1e-4);
    const int add = seg + 3 - static_cast<int>(fixed.cols());
    out.middleCols(ncp, add) = cp.middleCols(fixed.cols(), add);
    ncp += add;
    for (int s = 0; s < seg; ++s) {
      stitch.push_back(2 * s < seg ? piece.first : piece.second);
      kind.push_back(piece.kind);
    }
  }
  assert(ncp == total_seg + 3);
  return out;
}

// generate_knit for a first row knit from the left, or a pattern of several yarns
GeneratedKnit lay_knit(const Pattern& pattern_in, const KnitOptions& opt) {
  const Pattern pattern = tile(pattern_in, opt.rows, opt.cols);
  const Dims dims = resolve_dims(opt);
  const Layout layout(pattern, opt, dims);
  const int k = opt.segments_per_stitch;
  const int dense = 16 * k;

  // segment counts of turns and tails: about as long per segment as the stitches (tails: see
  // lay_tails)
  const double seg_len = plain_loop_length(dims) / k;
  const double turn_len = PI * 0.5 * dims.rh;
  const int k_turn = std::max(2, static_cast<int>(std::lround(turn_len / seg_len)));
  const std::vector<YarnRows> yarns = yarn_rows(pattern, opt);
  const std::map<std::pair<int, int>, int> lanes = carry_lanes(yarns);
  // carries run behind the free ends (z_back_of_row), lane by lane
  double z_carry = std::numeric_limits<double>::infinity();
  if (!lanes.empty())
    for (int row = 0; row < opt.rows; ++row)
      z_carry = std::min(z_carry, z_back_of_row(layout, opt, row));
  const double lane_step = 2.5 * opt.radius, carry_reach = 0.35 * dims.w;

  GeneratedKnit out;
  std::vector<Eigen::Matrix3Xd> blocks;
  std::vector<int> k_tails;
  for (int y = 0; y < static_cast<int>(yarns.size()); ++y) {
    const YarnRows& yr = yarns[y];
    std::vector<PieceSpec> pieces;
    pieces.push_back({});  // the start tail, made by lay_tails
    for (size_t j = 0; j < yr.rows.size(); ++j) {
      const int row = yr.rows[j];
      const bool forward = yr.forward[j];
      for (int i = 0; i < opt.cols; ++i) {
        const int col = forward ? i : opt.cols - 1 - i;
        pieces.push_back({layout.stitch_points(row, col, forward, dense),
                          k,
                          YarnPiece::STITCH,
                          {row, col},
                          {row, col}});
      }
      if (opt.in_the_round || j + 1 == yr.rows.size()) continue;
      const int edge = forward ? opt.cols - 1 : 0, next = yr.rows[j + 1];
      if (next == row + 1) {
        pieces.push_back({layout.turn_points(row, forward, 4 * k_turn),
                          k_turn,
                          YarnPiece::TURN,
                          {row, edge},
                          {next, edge}});
      } else {
        const double z_lane = z_carry - lane_step * lanes.at({y, static_cast<int>(j)});
        const Eigen::Matrix3Xd dense_carry =
            layout.carry_points(row, next, forward, z_lane, carry_reach, 64);
        const int k_carry =
            std::max(k_turn, static_cast<int>(std::lround(polyline_length(dense_carry) / seg_len)));
        pieces.push_back({layout.carry_points(row, next, forward, z_lane, carry_reach, 8 * k_carry),
                          k_carry,
                          YarnPiece::TURN,
                          {row, edge},
                          {next, edge}});
      }
    }
    k_tails.push_back(lay_tails(layout, opt, dims, seg_len, yr, 0, pieces));
    blocks.push_back(fit_pieces(pieces, layout, out.stitch, out.piece));
    out.yarn_segments.push_back(static_cast<int>(blocks.back().cols()) - 3);
  }
  int total_cp = 0;
  for (const auto& b : blocks) total_cp += static_cast<int>(b.cols());
  out.control_points.resize(3, total_cp);
  for (int y = 0, at = 0; y < static_cast<int>(blocks.size()); at += blocks[y].cols(), ++y)
    out.control_points.middleCols(at, blocks[y].cols()) = blocks[y];
  if (min_distance(out.control_points, opt.radius, CONTACT_POINTS, out.yarn_segments).ratio <
      SEPARATION_TARGET)
    separate_close_pairs(out.control_points, opt.radius, SEPARATION_TARGET, CONTACT_POINTS,
                         out.yarn_segments);
  const std::vector<int> first_cp = first_control_points(out.yarn_segments);

  // glue each free end to the closest point of its yarn outside its own tail and the stitch
  // it enters
  for (int y = 0, seg0 = 0, cp0 = 0; y < static_cast<int>(blocks.size()); ++y) {
    const int nseg = out.yarn_segments[y];
    const Eigen::Matrix3Xd cp = out.control_points.middleCols(cp0, nseg + 3);
    const int reach = k_tails[y] + k / 2;
    const Eigen::Vector3d start = cp.leftCols<4>() * bspline_basis(0.0);
    const Eigen::Vector3d end = cp.rightCols<4>() * bspline_basis(1.0);
    YarnPoint to_start = closest_point(cp, start, [&](int i) { return i >= reach; });
    YarnPoint to_end = closest_point(cp, end, [&](int i) { return i < nseg - reach; });
    to_start.segment += seg0;
    to_end.segment += seg0;
    out.glues.push_back({YarnPoint{seg0, 0.0}, to_start});
    out.glues.push_back({YarnPoint{seg0 + nseg - 1, 1.0}, to_end});
    seg0 += nseg;
    cp0 += nseg + 3;
  }
  if (opt.bind_off)
    for (int col = 0; col < opt.cols; ++col)
      for (const Glue& g : edge_ties(out.control_points, first_cp, out.stitch, out.piece,
                                     {opt.rows - 1, col}, {opt.rows - 2, col}))
        out.glues.push_back(g);
  // the cast-on: the same ties one row up from the bottom edge (the first row's heads are
  // where the second row's legs cross them); with 2 rows a bind-off has tied them already
  if (opt.cast_on && !(opt.bind_off && opt.rows == 2))
    for (int col = 0; col < opt.cols; ++col)
      for (const Glue& g :
           edge_ties(out.control_points, first_cp, out.stitch, out.piece, {1, col}, {0, col}))
        out.glues.push_back(g);
  for (const Glue& g : out.glues)
    out.glue_gap_cm.push_back((out.point(g.a) - out.point(g.b)).norm());

  // centre: a flat piece on the origin, a tube on its axis (y centred)
  Eigen::Vector3d centre =
      0.5 * (out.control_points.rowwise().minCoeff() + out.control_points.rowwise().maxCoeff());
  if (opt.in_the_round) centre.x() = centre.z() = 0;
  out.control_points.colwise() -= centre;

  // measured sizes
  out.stitch_width_cm = dims.w;
  out.row_height_cm = dims.rh;
  out.loop_depth_cm = dims.depth;
  const QuadratureTable quad = simpson_table(11);
  double stitch_len = 0;
  int nstitch_seg = 0;
  for (int i = 0; i < out.num_segments(); ++i)
    if (out.piece[i] == YarnPiece::STITCH) {
      Vector12d x;
      for (int a = 0; a < 4; ++a) x.segment<3>(3 * a) = out.control_points.col(first_cp[i] + a);
      stitch_len += segment_arclength(x, quad);
      ++nstitch_seg;
    }
  out.loop_length_cm = stitch_len / nstitch_seg * k;
  out.segments_per_turn = opt.in_the_round ? 0 : k_turn;
  out.segments_per_tail = k_tails.front();
  const MinDistance md =
      min_distance(out.control_points, opt.radius, CONTACT_POINTS, out.yarn_segments);
  out.min_distance_ratio = md.ratio;
  out.min_distance_segment_a = md.segment_a;
  out.min_distance_segment_b = md.segment_b;
  return out;
}

}  // namespace

GeneratedKnit generate_knit(const Pattern& pattern, const KnitOptions& opt) {
  check_options(pattern, opt);
  if (!pattern.first_row_leftward || !pattern.row_yarn.empty()) return lay_knit(pattern, opt);
  // the mirror image of the mirrored chart's knit
  Pattern mirrored = tile(pattern, opt.rows, opt.cols);
  mirrored.first_row_leftward = false;
  for (std::string& row : mirrored.rows) std::reverse(row.begin(), row.end());
  GeneratedKnit g = lay_knit(mirrored, opt);
  g.control_points.row(0) *= -1;
  for (StitchCoord& s : g.stitch)
    if (s.col >= 0) s.col = opt.cols - 1 - s.col;
  return g;
}

Eigen::Vector3d GeneratedKnit::point(const YarnPoint& p) const {
  // the segment's first control point: its index plus 3 for each yarn before its own
  int first = p.segment, local = p.segment;
  for (size_t y = 0; y < yarn_segments.size() && local >= yarn_segments[y]; ++y) {
    local -= yarn_segments[y];
    first += 3;
  }
  return control_points.middleCols<4>(first) * bspline_basis(p.t);
}

Model build_knit_model(const GeneratedKnit& knit, const Params& params, double rest_scale,
                       double glue_close_time) {
  ModelBuilder b;
  for (size_t y = 0, at = 0; y < knit.yarn_segments.size(); at += knit.yarn_segments[y] + 3, ++y)
    b.add_yarn(knit.control_points.middleCols(at, knit.yarn_segments[y] + 3));
  b.set_stitches(knit.stitch);
  for (Glue g : knit.glues) {
    if (glue_close_time > 0) {
      g.gap = knit.point(g.a) - knit.point(g.b);
      g.close_time = glue_close_time;
    }
    b.add_glue(g);
  }
  return b.build(params, rest_scale);
}

}  // namespace knit
