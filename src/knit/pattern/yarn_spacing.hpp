#pragma once
// How close the non-neighbouring parts of yarns come to each other, measured between
// contact points (the midpoint rule, as the contact energy samples the yarn), and a pass
// that pushes apart the parts that come too close. The knit generator uses both.
#include <Eigen/Core>
#include <span>

namespace knit {

/// Closest approach between non-neighbouring segments (segment indices count over all the
/// yarns, in order).
struct MinDistance {
  double ratio = 0;  ///< distance / (2 r)
  int segment_a = -1, segment_b = -1;
};

/// min over pairs of segments with |i − j| > 1 of the distance between their contact
/// points (`points_per_segment`, midpoint rule), divided by 2·radius. Uses a uniform grid
/// hash (cells of 3r); when no pair is closer than a cell it falls back to all pairs.
/// `yarn_segments` empty: `control_points` is one yarn; else they are the yarns' control
/// points one after the other, yarn y's yarn_segments[y] segments with yarn_segments[y] + 3
/// points (segments of different yarns are never neighbours).
MinDistance min_distance(const Eigen::Matrix3Xd& control_points, double radius,
                         int points_per_segment = 10, std::span<const int> yarn_segments = {});
/// The same by testing every pair (the slow oracle for tests).
MinDistance min_distance_brute_force(const Eigen::Matrix3Xd& control_points, double radius,
                                     int points_per_segment = 10,
                                     std::span<const int> yarn_segments = {});

/// Pushes apart the contact points of non-neighbouring segments closer than
/// `target`·2r by moving the control points of their two segments (see yarn_spacing.cpp).
/// It only ever separates, so yarns keep the sides of each other they were laid on.
void separate_close_pairs(Eigen::Matrix3Xd& control_points, double radius, double target,
                          int points_per_segment, std::span<const int> yarn_segments = {});

}  // namespace knit
