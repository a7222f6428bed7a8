#pragma once
// Sample segments for velocity filters (MODEL.md §5.3): every spline segment is split into
// n sample segments; a filter works on their midpoints, and the velocity changes it wants
// there become control-point impulses J_k = Σ_s m_s B_k(t_s) Δv_s, applied as Δq̇ = M⁻¹ J
// with the model's lumped mass.
//
// Sample masses: m_s = ℓ_i · (m_yarn / L_yarn) / n, where ℓ_i is the segment's rest length
// and m_yarn / L_yarn the yarn's lumped mass per unit of rest length. This is μ ℓ_i / n for
// a model built at its rest length, and stays consistent with the lumped mass when the rest
// lengths are shrunk (relaxation): the samples of a yarn always weigh what its control
// points weigh. Since Σ_k B_k = 1 and Σ_k B_k(t_s) q_k is the sample's position, the
// impulses change the control points' linear momentum Σ M_k q̇_k by Σ_s m_s Δv_s and their
// angular momentum Σ M_k q_k × q̇_k by Σ_s m_s x_s × Δv_s, exactly.
#include <Eigen/Core>
#include <vector>

#include "knit/model/model.hpp"

namespace knit {

class SampleSegments {
 public:
  /// Samples of every segment of `model` (samples_per_segment ≥ 1).
  explicit SampleSegments(const Model& model, int samples_per_segment = 8);

  int samples_per_segment() const { return m_per; }
  int num_samples() const { return static_cast<int>(m_mass.size()); }
  /// Sample s belongs to segment s / samples_per_segment, at t_s = (s mod n + 1/2) / n.
  int segment_of(int s) const { return s / m_per; }
  double mass(int s) const { return m_mass[s]; }  ///< g
  const std::vector<double>& masses() const { return m_mass; }
  /// B_a(t_k) of sample k of every segment (k < samples_per_segment).
  const Eigen::Vector4d& basis(int k) const { return m_basis[k]; }

  /// Midpoint positions (cm) of all samples, 3 × num_samples.
  Eigen::Matrix3Xd positions(const Model& model, const Eigen::VectorXd& q) const;
  /// The same into `out` (resized; no allocation when it already has the size).
  void positions(const Model& model, const Eigen::VectorXd& q, Eigen::Matrix3Xd& out) const;
  /// Midpoint velocities (cm/s): the same basis applied to the control-point velocities.
  Eigen::Matrix3Xd velocities(const Model& model, const Eigen::VectorXd& v) const;
  /// v += M⁻¹ J with J_k = Σ_s m_s B_k(t_s) dv_s (dv: 3 × num_samples, cm/s). Parallel and
  /// deterministic: per-segment sums, then a gather per control point in fixed order.
  void apply(const Model& model, const Eigen::Matrix3Xd& dv, Eigen::VectorXd& v) const;
  /// The same for the samples of `segments` alone (the others' dv is taken as zero), in
  /// the order given: serial, for a few segments at a time (a collision filter's).
  void apply_segments(const Model& model, const std::vector<int>& segments,
                      const Eigen::Matrix3Xd& dv, Eigen::VectorXd& v) const;

 private:
  int m_per;
  std::vector<double> m_mass;
  std::vector<Eigen::Vector4d> m_basis;  // B_a(t_k) for k < n
  // apply's per-segment impulses, kept between calls (no allocation per step)
  mutable std::vector<Vector12d> m_slot;
};

}  // namespace knit
