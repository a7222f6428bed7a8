#pragma once
// Recipe: "stretch the elastic sheet beside the knit" — the stretch test of stretch.hpp on
// a Baraff–Witkin sheet (sheet/) carrying the relaxed knit's geometry, as the paper set
// its yarn model beside a conventional cloth model.
//
// The sheet is the sample's mid-surface: the rectangle, in the plane through the control
// points' centroid normal to their direction of least spread, that bounds their
// projections along the course (u) and the wale (v, completing a right-handed frame with
// the normal), meshed regularly at `node_spacing`. Every control point is embedded
// barycentrically in its nearest triangle with its normal offset (sheet/embedding.hpp), so
// the sheet's deformation carries the yarn and the sheet is drawn as yarn. Each clamp
// holds the sheet's nodes within the extent (along the clamp's direction) of the control
// points the yarn test's clamp holds: the first or last columns (course), rows (wale), or
// a corner's stitches (bias: both ranges).
//
// The pull is quasi-static: for every sample the moving clamp's nodes are placed at that
// strain and the sheet's equilibrium is solved (Newton on the exact energy, no gravity), so
// the curve has no rate dependence. Its samples are the yarn test's: nominal strain of the
// clamps' centres, each clamp's force along the pull (tension > 0), the width across the
// pull at the middle (of the embedded yarn), the elastic energy. The outputs are
// stretch_knit's — frames (the embedded yarn, at the nominal time the yarn test's speed
// gives), stretch.csv, summary.json (model "sheet", the material, the mesh and the fit),
// plots, renders — so `knitsim stretch --plot` and the renders treat both alike.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "knit/recipes/stretch.hpp"
#include "knit/sheet/sheet.hpp"

namespace knit {

struct SheetStretchOptions {
  StretchOptions stretch;         ///< direction, strain, cycles, clamps, outputs (speed: time)
  sheet::SheetMaterial material;  ///< stiffnesses (density and damping unused in statics)
  double node_spacing = 0.5;      ///< cm between grid nodes (about half a stitch)
  nlohmann::json fit = nullptr;   ///< how the material was fitted (into the summary)
};

/// The sheet of a relaxed knit (see above) and its embedding, without running anything.
struct KnitSheet {
  sheet::SheetMesh mesh;
  std::vector<int> fixed_nodes, moving_nodes;
  Eigen::Matrix3Xd embedded;  ///< the embedded control points as placed (cm)
  Eigen::Vector3d u_axis, v_axis, normal;
  double width = 0, height = 0;  ///< along u (course) and v (wale), cm
};
KnitSheet make_knit_sheet(const StretchGeometry& geometry, double node_spacing);

/// Runs the quasi-static stretch test of the sheet. Throws std::invalid_argument naming
/// the option on bad input, before anything is written.
StretchResult stretch_sheet(const std::string& kstate_path, const SheetStretchOptions& options);

/// The sheet material fitted to stretch runs of the yarn model (directories written by
/// `knitsim stretch`): the course run's small-strain stiffness (stretch.stiffness_small_strain,
/// dyn per unit strain) sets k_stretch_u, the wale run's k_stretch_v, a bias run's k_shear
/// (each found by solving the sheet's statics at the small-strain window's middle on the
/// same knit, `kstate_path`, and scaling or bisecting until the sheet's stiffness is the
/// yarn model's within 0.1 %). Directions not given keep `base`'s values. The report says
/// what was fitted to what.
struct SheetFit {
  sheet::SheetMaterial material;
  nlohmann::json report;
};
SheetFit fit_sheet_material(const std::string& kstate_path, const std::vector<std::string>& runs,
                            const SheetStretchOptions& base);

}  // namespace knit
