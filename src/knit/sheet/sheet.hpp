#pragma once
// Elastic-sheet cloth (Baraff & Witkin 1998, "Large steps in cloth simulation"): the
// triangle mesh and its material, used beside the yarn model for stretch-test comparisons.
// Self-contained: depends on Eigen and the standard library only, not on the rest of knit.
//
// Units are CGS throughout: positions and material coordinates cm, areas cm², masses g,
// forces dyn, energies erg.
//
// Every triangle carries material coordinates (u, v) per vertex (BW §4.2); u is the
// "course" direction and v the "wale" direction of the fabric. With
//   D = [Δu1 Δu2; Δv1 Δv2]   (Δu_k = u_k − u_0, Δv_k = v_k − v_0, cm)
// the deformation gradient of the triangle is [w_u w_v] = [Δx1 Δx2] D⁻¹ (dimensionless),
// and its rest area is a = ½ |det D| (cm²). Interior edges ("hinges") carry the four
// vertices the bending condition needs.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <vector>

namespace knit::sheet {

/// Default areal density of SheetMaterial and make_rectangle, g/cm² (200 g/m², a
/// medium-weight knit).
inline constexpr double DEFAULT_SHEET_DENSITY = 0.02;

/// Stiffness and damping of the three Baraff–Witkin conditions (see bw_energy.hpp for
/// the exact energies). The stretch stiffness may differ along u (course) and v (wale), as
/// a knit's does. The defaults describe a soft knit swatch: a 2-D stretch modulus of
/// 100 N/m both ways, shear one tenth of it, a bending rigidity of 1 erg = 1e-7 N·m, and
/// damping time constants k_d / k of 1 ms.
struct SheetMaterial {
  /// Stretch stiffness along u, dyn/cm: E = ½ k_stretch_u a (‖w_u‖ − 1)² per triangle, so
  /// k_stretch_u is the sheet's 2-D Young modulus along u (force per width per strain).
  double k_stretch_u = 1e5;
  /// Stretch stiffness along v, dyn/cm: E = ½ k_stretch_v a (‖w_v‖ − 1)² per triangle.
  double k_stretch_v = 1e5;
  /// Shear stiffness, dyn/cm: E = ½ k_shear a (w_u·w_v)² per triangle.
  double k_shear = 1e4;
  /// Bending stiffness, erg (dyn·cm): E = ½ k_bend (θ − θ₀)² per interior edge.
  double k_bend = 1.0;
  /// Stretch condition damping, s·dyn/cm (BW §4.5: d = −k_d ∂C/∂x Ċ).
  double d_stretch = 100.0;
  /// Shear condition damping, s·dyn/cm.
  double d_shear = 10.0;
  /// Bending condition damping, s·erg.
  double d_bend = 1e-3;
  /// Mass per area, g/cm². The mesh carries the lumped masses the solver uses
  /// (SheetMesh::mass): pass this to make_rectangle / make_sheet_mesh, or set_density.
  double density = DEFAULT_SHEET_DENSITY;
};

/// One interior edge shared by two triangles, for the bending condition. With
/// x1 = opposite[0], x2 = opposite[1], x3 = edge[0], x4 = edge[1] (Bridson, Marino & Fedkiw
/// 2003's numbering) the triangles are (x1, x3, x4) and (x2, x4, x3).
struct SheetHinge {
  std::array<int, 2> edge{};      ///< the shared edge's end nodes
  std::array<int, 2> opposite{};  ///< the node opposite the edge in each triangle
  double rest_angle = 0;          ///< θ₀, radians, the dihedral angle in the rest shape
  double rest_area_product = 1;  ///< ‖n1⁰‖ ‖n2⁰‖, cm⁴ (bend_area_product in the rest shape)
};

/// Immutable sheet model: rest shape, material coordinates and lumped masses. Build it with
/// make_sheet_mesh or make_rectangle; changing its topology afterwards invalidates the
/// assembly cache (clear jacobian_pattern to fall back to the plain assembly).
struct SheetMesh {
  Eigen::Matrix3Xd rest;                      ///< rest positions, cm, one column per node
  Eigen::Matrix2Xd uv;                        ///< material coordinates (u, v), cm, per node
  std::vector<std::array<int, 3>> triangles;  ///< node indices per triangle
  std::vector<Eigen::Matrix2d> dinv;  ///< per triangle D⁻¹ = [Δu1 Δu2; Δv1 Δv2]⁻¹, 1/cm
  std::vector<double> area;           ///< per triangle rest area a = ½|det D|, cm²
  std::vector<SheetHinge> hinges;     ///< interior edges
  Eigen::VectorXd node_area;          ///< ⅓ of the adjacent triangles' areas, cm²
  Eigen::VectorXd mass;               ///< lumped masses = density · node_area, g
  int nu = 0;                         ///< grid nodes along u (make_rectangle), 0 for a general mesh
  int nv = 0;                         ///< grid nodes along v (make_rectangle), 0 for a general mesh

  /// Assembly cache filled by make_sheet_mesh: the Jacobians' sparsity (3×3 blocks for node
  /// pairs sharing a triangle or hinge, explicit zeros), and for each element's node pair
  /// (a, b) the offset of entry (3·node_a, 3·node_b) from its column's start. Without it
  /// (empty pattern) evaluate_forces assembles from triplets, which is slower.
  Eigen::SparseMatrix<double> jacobian_pattern;
  std::vector<std::array<int, 9>> triangle_slots;  ///< per triangle, 3×3 node pairs
  std::vector<std::array<int, 16>> hinge_slots;    ///< per hinge, 4×4 node pairs

  /// Number of nodes.
  int num_nodes() const { return static_cast<int>(rest.cols()); }
  /// Number of degrees of freedom (3 per node).
  int num_dofs() const { return 3 * num_nodes(); }
  /// Rest positions stacked as (x0, y0, z0, x1, …), cm.
  Eigen::VectorXd rest_positions() const;
};

/// Builds a sheet from rest positions (cm), per-node material coordinates (cm) and
/// triangles; computes D⁻¹, areas, hinges (edges shared by exactly two triangles, their
/// rest angles from the rest positions) and lumped masses with `density` (g/cm²).
/// Throws std::invalid_argument for mismatched sizes, out-of-range indices, triangles of
/// (near-)zero material area or zero rest area in 3-D at a bending edge, edges shared by
/// more than two triangles or density <= 0.
SheetMesh make_sheet_mesh(Eigen::Matrix3Xd rest, Eigen::Matrix2Xd uv,
                          std::vector<std::array<int, 3>> triangles,
                          double density = DEFAULT_SHEET_DENSITY);

/// A regular grid of nu×nv nodes over width×height (cm) in the plane through `origin`
/// spanned by u_axis and v_axis (normalised here, and v made orthogonal to u; they must be
/// non-zero and not parallel).
/// Node (i, j), 0 <= i < nu along u and 0 <= j < nv along v, has index j·nu + i, rest
/// position origin + u·û + v·v̂ and material coordinates (u, v) = (i·width/(nu−1),
/// j·height/(nv−1)). Each quad is split in two triangles along a diagonal that alternates
/// like a checkerboard so the mesh has no preferred shear direction. Throws
/// std::invalid_argument for width or height <= 0, nu or nv < 2, bad axes or density <= 0.
SheetMesh make_rectangle(const Eigen::Vector3d& origin, const Eigen::Vector3d& u_axis,
                         const Eigen::Vector3d& v_axis, double width, double height, int nu, int nv,
                         double density = DEFAULT_SHEET_DENSITY);

/// Recomputes the lumped masses for another areal density (g/cm², > 0).
void set_density(SheetMesh& mesh, double density);

/// Node index of grid node (i, j) of a make_rectangle mesh.
int grid_node(const SheetMesh& mesh, int i, int j);
/// The nv nodes of grid column i (constant u), for a clamp across a u end.
std::vector<int> grid_column(const SheetMesh& mesh, int i);
/// The nu nodes of grid row j (constant v), for a clamp across a v end.
std::vector<int> grid_row(const SheetMesh& mesh, int j);

}  // namespace knit::sheet
