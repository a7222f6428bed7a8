#pragma once
// A relaxation's rest shape against a reference relaxation of the same knit: the check
// that a quick relaxation (FIRE) reaches the rest a long one reached
// (`bench_relax_to_rest --reference DIR`, scripts/relax_reference.sh).
//
// Both sides are `knitsim relax` summaries (summary.json), whose shape measures are
// FabricShape's (fabric_shape.hpp): lengths along the fabric (cm), gauge (cm per stitch
// and per row), extents (cm) and the edge curl (stitch widths).
#include <nlohmann/json.hpp>
#include <string>

namespace knit {

/// The shape measures compared, in order: width and height along the fabric, the gauge,
/// the extents (which a rolled edge shortens) and the edge curl.
inline constexpr const char* REST_SHAPE_KEYS[] = {
    "course_length_cm", "wale_length_cm", "stitch_width_cm", "row_height_cm",
    "course_extent_cm", "wale_extent_cm", "edge_curl"};

/// Reads DIR/PATTERN/summary.json, the summary of a `knitsim relax` run of PATTERN at
/// rows × cols that came to rest ("relaxed": true) and has every REST_SHAPE_KEYS measure
/// as a finite number. Throws std::runtime_error naming the file and what is wrong.
nlohmann::json read_rest_reference(const std::string& dir, const std::string& pattern, int rows,
                                   int cols);

/// `run`'s shape against `reference`'s (both summaries, or any objects with the
/// REST_SHAPE_KEYS measures): each measure's relative difference run / reference − 1 under
/// its own key, except the edge curl, whose difference run − reference (stitch widths) is
/// "edge_curl_difference" (a relative difference of two nearly flat edges means nothing);
/// and "max_abs_width_height_gauge", the largest |relative difference| of the lengths
/// along the fabric and the gauge. A measure missing or not a number on either side, or
/// 0 in the reference, is left out (and out of the largest).
nlohmann::json compare_rest_shape(const nlohmann::json& run, const nlohmann::json& reference);

}  // namespace knit
