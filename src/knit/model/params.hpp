#pragma once
// Physical and numerical parameters (MODEL.md §8, Table 1). CGS units throughout.
#include <Eigen/Core>

namespace knit {

struct Params {
  double radius = 0.125;                ///< yarn radius r (cm)
  double density = 0.006;               ///< mass per unit length μ (g/cm)
  double k_len = 2000;                  ///< length energy stiffness (g cm²/s²)
  double k_bend = 5;                    ///< bending stiffness (g cm³/s²)
  double k_global = 0;                  ///< global (mass-proportional) damping (g/s)
  double k_contact = 3250;              ///< yarn–yarn contact stiffness (erg/cm² = g/s²)
  double k_dt = 0.003;                  ///< tangential contact damping (g/(cm² s))
  double k_dn = 0.03;                   ///< normal contact damping (g/(cm² s))
  double alpha_small = 0.675;           ///< non-rigid damping, small regions ∈ [0,1]
  double alpha_large = 0.3;             ///< non-rigid damping, large regions ∈ [0,1]
  Eigen::Vector3d gravity{0, 0, -981};  ///< cm/s²
  int quadrature_points = 11;           ///< Simpson points per segment for the energies (odd)
  int contact_points = 10;              ///< contact quadrature points per segment
  bool length_constraints = true;       ///< enforce C_i = 0 by projection (off in relaxation)
  bool contact = true;                  ///< yarn–yarn contact on/off
  double constraint_tolerance = 1e-6;   ///< projection stops when max |C| is below (C_len is
                                        ///< dimensionless, pin/glue rows in cm)
  int max_projection_iterations = 20;

  /// MODEL.md §8, simulation column.
  static Params simulation() { return Params{}; }
  /// MODEL.md §8, relaxation column (length constraints off, strong global damping).
  static Params relaxation() {
    Params p;
    p.k_len = 10000;
    p.k_bend = 0.005;
    p.k_global = 1.5;
    p.alpha_small = 0.3;
    p.alpha_large = 0.3;
    p.length_constraints = false;
    return p;
  }
};

}  // namespace knit
