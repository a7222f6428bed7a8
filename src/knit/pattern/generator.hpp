#pragma once
// Builds the initial yarn geometry of a knitted piece (MODEL.md §6): one continuous yarn
// laid stitch by stitch from a closed-form loop curve, each stitch fitted with a fixed
// number of cubic B-spline segments that continue C² from the control points already laid;
// where the fitted yarn still comes closer to itself than 0.9 of a yarn diameter, the
// pieces are pushed apart (see min_distance_ratio).
//
// Coordinates (cm): x along the course (rows run along x), y along the wale (rows stack in
// +y), z out of the fabric (front face = +z). The flat fabric is centred at the origin; a
// tube knitted in the round has its axis on the y axis and its front face outside.
#include <Eigen/Core>
#include <vector>

#include "knit/model/model.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/pattern/yarn_spacing.hpp"

namespace knit {

/// Options of generate_knit. Lengths in cm; 0 means "derive from the radius". The default
/// proportions are Crane's plain-knit loop, a little opened (see generator.cpp): for
/// r = 0.125 cm a stitch is 0.98 cm wide, rows are 0.74 cm apart, yarns that cross are
/// 0.44 cm apart in z (loop_depth) and a plain loop uses about 4.1 cm of yarn.
struct KnitOptions {
  int rows = 6;                       ///< courses (rows) of the piece
  int cols = 6;                       ///< stitches per row (around the tube when in_the_round)
  int segments_per_stitch = 8;        ///< spline segments fitted to each stitch (≥ 4)
  bool in_the_round = false;          ///< knit a tube (helix, no turns) instead of a flat piece
  double radius = Material{}.radius;  ///< yarn radius r (cm), the material default
  /// "Stitch size": yarn length per stitch (cm), the one knob a knitter turns by changing
  /// needles. When > 0 it scales the stitch width and row height together (the depth stays
  /// tied to the yarn) so that a plain (stockinette) loop uses this much yarn.
  double stitch_size_cm = 0;
  double stitch_width_cm = 0;  ///< course spacing of the loops (cm), 0 = default
  double row_height_cm = 0;    ///< wale spacing of the rows (cm), 0 = default
  double loop_depth_cm = 0;    ///< z distance between yarns where they cross (cm), 0 = default
  /// Secure the last row's live loops, as a sewn bind-off does: each is tied (glued) to the
  /// loop below it where its two legs cross that loop's head, so that a pull on the top edge
  /// cannot draw its loops out and ladder them down. Needs at least 2 rows. Off by default:
  /// the top loops are live, as on the needles.
  bool bind_off = false;
  /// Secure the first row as a cast-on does: each loop of the second row is tied (glued)
  /// where its two legs cross the head of the first row's loop below it, so that a pull
  /// cannot draw the first row's yarn out of the fabric (the first row has no loops below
  /// to hold it). Needs at least 2 rows. Off by default. With 2 rows and bind_off, the
  /// bind-off's ties already are these.
  bool cast_on = false;
};

/// What part of the yarn a segment belongs to.
enum class YarnPiece {
  STITCH,  ///< the loop of one stitch (sinker to sinker)
  TURN,    ///< the arc at the end of a row where a flat piece doubles back, or a yarn
           ///< carried up the edge to its next row past other yarns' rows
  TAIL,    ///< the free start or end, looped back behind the fabric and glued (a tube's end,
           ///< which the first stitch of its last round leaves no room to loop beside, runs on
           ///< along the course across the back or front of its last round instead)
};

/// The generated yarns: one, or a pattern's several (Pattern::row_yarn). Segments are
/// counted over all the yarns, in order; segment i of a single yarn is shaped by control
/// points i … i+3.
struct GeneratedKnit {
  /// the yarns' control points one after the other (cm): yarn y's yarn_segments[y]
  /// segments have yarn_segments[y] + 3
  Eigen::Matrix3Xd control_points;
  std::vector<int> yarn_segments;
  std::vector<StitchCoord> stitch;  ///< per segment; every segment has a stitch (turns
                                    ///< belong half to each row's edge stitch, tails to the
                                    ///< stitch they enter or leave)
  std::vector<YarnPiece> piece;     ///< per segment
  std::vector<Glue> glues;          ///< each free end glued to its yarn's closest point
                                    ///< (yarn by yarn, two each); with
                                    ///< bind_off, then the bind-off's ties, two per stitch
                                    ///< of the last row in column order; with cast_on, then
                                    ///< the cast-on's, two per stitch of the second row
  double stitch_width_cm = 0;
  double row_height_cm = 0;
  double loop_depth_cm = 0;
  double loop_length_cm = 0;  ///< mean yarn length of one stitch's segments
  /// min over non-neighbouring segment pairs (|i − j| > 1) of the distance between their
  /// contact points (10 per segment, midpoint rule) divided by 2r; ≥ 1: no overlap. The
  /// model's plain loop comes within 0.918 of itself (flat stockinette and garter: 0.918,
  /// flat ribs 0.935–0.976, as laid); closer pairs (seed, a tube's seam and ends) are pushed
  /// apart to 0.9 after the fit, so this is at least 0.9 unless the pushes fail to converge.
  double min_distance_ratio = 0;
  int min_distance_segment_a = -1, min_distance_segment_b = -1;  ///< where it occurs
  /// gap |y(a) − y(b)| of each glue as generated (cm): the ends lie against the fabric,
  /// about one yarn diameter from the point they are glued to; a bind-off or cast-on
  /// tie's gap is where the yarns cross and touch, about a yarn diameter.
  std::vector<double> glue_gap_cm;
  int segments_per_turn = 0;
  int segments_per_tail = 0;

  int num_segments() const { return static_cast<int>(stitch.size()); }
  int num_yarns() const { return static_cast<int>(yarn_segments.size()); }
  /// y(p), p's segment counted over all the yarns
  Eigen::Vector3d point(const YarnPoint& p) const;
};

/// Lays out `pattern` tiled to options.rows × options.cols (pattern row 0 at the bottom,
/// column 0 at the left as seen from the front). Row 0's yarn runs from the left, or with
/// pattern.first_row_leftward from the right: the mirror image (x → −x) of the knit of the
/// mirrored chart, whose stitches are the same (a loop of the model is symmetric about its
/// column's centre); a tube's columns then sit one column further round. Segment count: rows·cols·k
/// stitches, plus segments_per_turn for each of the rows − 1 turns of a flat piece, plus
/// segments_per_tail at each end; control points = segments + 3. Throws
/// std::invalid_argument naming the option on bad input.
GeneratedKnit generate_knit(const Pattern& pattern, const KnitOptions& options);

/// A model holding the knit as its only yarn, with its stitch coordinates and glues. With
/// `glue_close_time` > 0 every glue starts at its generated gap and closes over that time
/// (s); with 0 the glue holds the ends together from the start.
Model build_knit_model(const GeneratedKnit& knit, const Params& params, double rest_scale = 1.0,
                       double glue_close_time = 0);

}  // namespace knit
