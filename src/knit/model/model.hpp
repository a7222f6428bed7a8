#pragma once
// The immutable Model: topology of the yarns, rest lengths, lumped masses, constraints
// and quadrature tables. Everything that changes in time lives in State.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "knit/model/params.hpp"
#include "knit/spline/basis.hpp"

namespace knit {

/// One yarn: a contiguous range of control points and of segments.
struct YarnInfo {
  int cp_begin = 0, cp_end = 0;    ///< global control-point indices [begin, end)
  int seg_begin = 0, seg_end = 0;  ///< global segment indices [begin, end)
  int num_cp() const { return cp_end - cp_begin; }
  int num_seg() const { return seg_end - seg_begin; }
};

/// A point on a yarn: global segment index and the parameter t ∈ [0,1] in it.
struct YarnPoint {
  int segment = 0;
  double t = 0;
};

/// Where a segment lies in the knitted fabric (−1 when it is not part of one).
struct StitchCoord {
  int row = -1, col = -1;
};

/// Pin constraint y(s) − p(time) = 0 with p moving linearly with `velocity` between
/// `start` and `stop` (s), held still before and after.
struct Pin {
  YarnPoint at;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();    ///< p at time ≤ start (cm)
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();  ///< cm/s
  double start = 0;
  double stop = std::numeric_limits<double>::infinity();
  Eigen::Vector3d target(double time) const {
    const double tau = std::clamp(time, start, stop) - start;
    return origin + velocity * tau;
  }
};

/// Glue constraint y(a) − y(b) = g(time). The gap g starts at `gap` and closes linearly
/// to 0 over `close_time` seconds, so a yarn end laid next to the point it is glued to is
/// drawn in smoothly instead of snapped (which would kink the yarn's light end). With
/// close_time = ∞ the gap is held as it is.
struct Glue {
  YarnPoint a, b;
  Eigen::Vector3d gap = Eigen::Vector3d::Zero();  ///< cm at time 0
  double close_time = 0;                          ///< s
  Eigen::Vector3d offset(double time) const {
    if (close_time <= 0 || time >= close_time) return Eigen::Vector3d::Zero();
    return gap * (1.0 - std::max(time, 0.0) / close_time);
  }
};

/// A rigid pose of a clamp's frame at a time: the held points x₀ (as at time 0) go to
/// centre + translation + R (x₀ − centre), R = rotation.
struct Keyframe {
  double time = 0;                                        ///< s
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();  ///< cm
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

/// The pose along `keyframes` (by increasing time) at `time`: translation interpolated
/// linearly, rotation by slerp, held before the first keyframe and after the last; no
/// keyframes: the identity.
Keyframe interpolate_keyframes(const std::vector<Keyframe>& keyframes, double time);
/// The rates of that pose at `time`: d(translation)/dt (cm/s) and the angular velocity ω
/// (rad/s, world axes) of the rotation, constant between two keyframes (those of the
/// interval starting at `time`; zero before the first keyframe and from the last one on).
void keyframe_rates(const std::vector<Keyframe>& keyframes, double time, Eigen::Vector3d& velocity,
                    Eigen::Vector3d& omega);

/// Clamp: a set of yarn points held rigidly to a frame that moves along keyframes
/// (translation interpolated linearly, rotation by slerp, held before the first keyframe
/// and after the last; no keyframes: held still).
struct Clamp {
  std::string name;
  std::vector<YarnPoint> points;  ///< yarn points held
  /// control points held (global indices): a knit's rows or columns are held by the
  /// control points of their segments, which fixes those segments' shape exactly —
  /// their length rows, and glues whose points all lie on such segments, are then left to
  /// the clamp (see build_constraint_groups, constraints/groups.hpp)
  std::vector<int> control_points;
  /// the position at time 0 (cm) of each held point, then of each held control point
  std::vector<Eigen::Vector3d> rest;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  ///< centroid of `rest`: the pivot (cm)
  std::vector<Keyframe> keyframes;                   ///< by increasing time
  /// The frame's pose at `time` (translation and rotation, interpolated).
  Keyframe pose(double time) const;
  /// Where held point k (points first, then control points) is at `time` (cm).
  Eigen::Vector3d target(int k, double time) const {
    const Keyframe p = pose(time);
    return centre + p.translation + p.rotation * (rest[k] - centre);
  }
};

/// How a generated knit was being relaxed when a state of it was written: the relax
/// recipe's solver and rest-test settings (RelaxKnitOptions), so that `relax --resume`
/// goes on the same way unless told otherwise.
struct KnitRelaxSettings {
  bool fire = false;  ///< minimisation (FIRE) instead of damped dynamics
  /// The relaxation's parameters, as asked (k_global too, though a FIRE relaxation runs
  /// with none); a state records those relax_setting_params() names.
  Params params;
  double ke_per_length = 0;   ///< erg/cm: the kinetic-energy rest threshold
  double force_residual = 0;  ///< cm/s²: the force-residual rest threshold (0: the method's)
  int check_every = 0;        ///< steps between rest checks
  double contact_reuse_widen = 1;
  double contact_reuse_widen_residual = 0;  ///< cm/s²
};

/// The parameters (params.def names) a relaxation records in the states it writes: its
/// solver, sampling and damping, which `relax --resume` takes up again.
const std::vector<std::string>& relax_setting_params();

/// Where a model's yarn came from when it is a generated knit: enough to rebuild the same
/// knit or to go on relaxing it (written into .kstate files with the rest lengths and
/// glues).
struct KnitInfo {
  std::string pattern;  ///< built-in name or chart path, as given
  int rows = 0, cols = 0;
  bool in_the_round = false;
  int segments_per_stitch = 8;
  double stitch_size_cm = 0;  ///< 0 = the default for the yarn
  double shrink = 1;          ///< rest-length factor c the model was built with
  bool bind_off = false;      ///< the last row is bound off (KnitOptions::bind_off)
  bool cast_on = false;       ///< the first row is cast on (KnitOptions::cast_on)
  /// How it was being relaxed (set by the relax recipe; absent in files written before)
  std::optional<KnitRelaxSettings> relaxation;
};

class ConstraintGroup;
struct SceneObject;

class Model {
 public:
  Params params;
  std::vector<YarnInfo> yarns;
  std::vector<int> seg_cp;          ///< first control point of each segment
  std::vector<int> seg_yarn;        ///< yarn of each segment
  std::vector<double> rest_length;  ///< ℓ_i (cm), already scaled by any shrink factor
  std::vector<StitchCoord> stitch;  ///< per segment (may be all −1)
  Eigen::VectorXd mass;             ///< lumped mass per control point (g)
  Eigen::VectorXd inv_mass3;        ///< 1/m per coordinate (length 3·num_cp)
  std::vector<Pin> pins;
  std::vector<Glue> glues;
  std::vector<Clamp> clamps;
  /// Solid objects the yarn collides with (objects/object.hpp). Shared, immutable.
  std::vector<std::shared_ptr<const SceneObject>> objects;
  /// Set when the yarn is a generated knit (see KnitInfo).
  std::optional<KnitInfo> knit;
  /// The rows the projection enforces: "length" (when solver.length_constraints), then
  /// one group per pin ("pin0", …), per glue ("glue0", …) and per clamp (its name), in
  /// that order. Shared, immutable. Built from the pins, glues and clamps above by
  /// build_constraint_groups (constraints/groups.hpp), which the Simulator calls on the
  /// model it is given: a Model fresh from ModelBuilder::build has none.
  std::vector<std::shared_ptr<const ConstraintGroup>> constraint_groups;
  QuadratureTable quad;          ///< energy quadrature (Simpson)
  QuadratureTable contact_quad;  ///< contact quadrature (midpoint)

  int num_cp() const { return static_cast<int>(mass.size()); }
  int num_seg() const { return static_cast<int>(seg_cp.size()); }
  int num_dof() const { return 3 * num_cp(); }
  bool has_stitches() const;
  /// Segment pairs (i < j, sorted) that do not interact through contact although they are
  /// not neighbours: the segments around each glue (GLUE_CONTACT_EXCLUSION on each side of
  /// both glued points). A glued yarn end is tied into the fabric, and the point it is glued
  /// to lies on another piece of yarn: contact there would fight the glue.
  std::vector<std::pair<int, int>> contact_exclusions;

  /// true when segments i and j do not interact through contact: the same yarn with
  /// |i − j| ≤ 1, or a pair in contact_exclusions.
  bool neighbours(int i, int j) const {
    if (seg_yarn[i] == seg_yarn[j] && std::abs(i - j) <= 1) return true;
    if (contact_exclusions.empty()) return false;
    return std::binary_search(contact_exclusions.begin(), contact_exclusions.end(),
                              std::pair<int, int>(std::min(i, j), std::max(i, j)));
  }
  /// Total yarn rest length (cm).
  double total_length() const;
  /// The yarn that holds global control point `cp` (its index in `yarns`).
  int yarn_of_cp(int cp) const {
    const auto it = std::upper_bound(yarns.begin(), yarns.end(), cp,
                                     [](int c, const YarnInfo& y) { return c < y.cp_end; });
    return static_cast<int>(it - yarns.begin());
  }
};

/// Segments on each side of a glued point that are kept out of contact with the other
/// glued point's segments.
inline constexpr int GLUE_CONTACT_EXCLUSION = 2;

/// Builds a Model from control points; rest lengths are the initial arclengths
/// (measured with the model's own quadrature, so C_i = 0 initially).
class ModelBuilder {
 public:
  /// Adds a yarn (≥ 4 control points, one per column). Returns its index.
  int add_yarn(const Eigen::Matrix3Xd& control_points);
  void add_pin(const Pin& pin) { m_pins.push_back(pin); }
  void add_glue(const Glue& glue) { m_glues.push_back(glue); }
  /// Adds a clamp (its points' rest positions and centre are taken from the control
  /// points when the model is built; a clamp without a name is called "clamp<k>").
  void add_clamp(Clamp clamp) { m_clamps.push_back(std::move(clamp)); }
  /// Stitch coordinates for every segment of every yarn added so far.
  void set_stitches(std::vector<StitchCoord> stitches) { m_stitch = std::move(stitches); }
  int num_yarns() const { return static_cast<int>(m_yarns.size()); }
  int num_segments() const;
  /// Global segment index of segment `local` of yarn `yarn` (throws if out of range).
  int segment_index(int yarn, int local) const;
  /// Control points of all yarns, stacked (3·num_cp).
  Eigen::VectorXd positions() const;
  /// Builds the model. Mass uses the unshrunk rest lengths; `rest_scale` (the relaxation
  /// shrink factor c) multiplies every ℓ_i.
  Model build(const Params& params, double rest_scale = 1.0) const;

 private:
  std::vector<Eigen::Matrix3Xd> m_yarns;
  std::vector<Pin> m_pins;
  std::vector<Glue> m_glues;
  std::vector<Clamp> m_clamps;
  std::vector<StitchCoord> m_stitch;
};

/// Arclength ∫₀¹|y'(t)|dt of one segment with the given quadrature (cm).
double segment_arclength(const Vector12d& x, const QuadratureTable& quad);

/// A copy of `model` with every rest length multiplied by `scale` (mass unchanged).
Model scale_rest_lengths(const Model& model, double scale);

/// Raises the lumped mass (and inverse mass) of the two control points at each end of
/// every yarn of at least 8 control points to `fraction` of that yarn's mean interior
/// control point's (Discretisation::end_mass_floor; ModelBuilder::build applies the
/// model's own). Does nothing for fraction ≤ 0.
void apply_end_mass_floor(Model& model, double fraction);

/// Position y(s) of a yarn point.
Eigen::Vector3d point_position(const Model& model, const Eigen::VectorXd& q, const YarnPoint& p);

}  // namespace knit
