#pragma once
// Bounding volume hierarchy for contact culling (MODEL.md §7): a binary tree of
// axis-aligned boxes over a fixed set of leaves (one per spline segment). The topology is
// built once from the first positions by median splits and only refit afterwards, since
// the yarn topology never changes.
#include <Eigen/Core>
#include <algorithm>
#include <cassert>
#include <limits>
#include <vector>

namespace knit {

/// Axis-aligned box [lo, hi] (cm).
struct Aabb {
  Eigen::Vector3d lo{Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity())};
  Eigen::Vector3d hi{Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity())};

  void extend(const Eigen::Vector3d& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  /// The box grown by `margin` on every side.
  Aabb grown(double margin) const {
    Aabb b;
    b.lo = lo.array() - margin;
    b.hi = hi.array() + margin;
    return b;
  }
  /// Closed-interval overlap on all three axes.
  bool overlaps(const Aabb& b) const {
    return lo[0] <= b.hi[0] && b.lo[0] <= hi[0] && lo[1] <= b.hi[1] && b.lo[1] <= hi[1] &&
           lo[2] <= b.hi[2] && b.lo[2] <= hi[2];
  }
  bool contains(double x, double y, double z) const {
    return x >= lo[0] && x <= hi[0] && y >= lo[1] && y <= hi[1] && z >= lo[2] && z <= hi[2];
  }
};

/// A BVH over `n` leaf boxes. Nodes are stored in preorder (a parent before its
/// children, the left child right after its parent), so a refit is one reverse sweep.
class Bvh {
 public:
  /// Builds the tree topology from `leaves` (top-down, median split on the longest axis
  /// of the box centres) and sets the node boxes.
  void build(const std::vector<Aabb>& leaves);
  /// Recomputes every node box from moved leaves (same count as at build time).
  void refit(const std::vector<Aabb>& leaves);
  bool empty() const { return m_nodes.empty(); }
  int num_leaves() const { return m_num_leaves; }
  int num_nodes() const { return static_cast<int>(m_nodes.size()); }

  /// Calls on_leaf(leaf index) for every leaf whose box overlaps `box`, in a fixed order
  /// (depth first, left before right). Returns the number of node boxes tested. With
  /// `after` ≥ 0, only leaves with a larger index: a subtree whose leaves all come at or
  /// before it is skipped untested (each pair found once, from its lower leaf).
  template <class F>
  long long query(const Aabb& box, F&& on_leaf, int after = -1) const;

 private:
  struct Node {
    Aabb box;
    int right = -1;     ///< index of the right child (the left one is this index + 1)
    int leaf = -1;      ///< leaf index, or −1 for an inner node
    int max_leaf = -1;  ///< the largest leaf index in the subtree
  };
  int build_range(std::vector<int>& order, std::vector<Eigen::Vector3d>& centres, int begin,
                  int end);

  std::vector<Node> m_nodes;
  int m_num_leaves = 0;
};

template <class F>
long long Bvh::query(const Aabb& box, F&& on_leaf, int after) const {
  if (m_nodes.empty()) return 0;
  // the tree is balanced (median splits), so its depth is ≈ log2(n) + 1
  constexpr int MAX_DEPTH = 96;
  int stack[MAX_DEPTH];
  int top = 0;
  stack[top++] = 0;
  long long tests = 0;
  while (top > 0) {
    const int k = stack[--top];
    const Node& node = m_nodes[k];
    if (node.max_leaf <= after) continue;
    ++tests;
    if (!node.box.overlaps(box)) continue;
    if (node.leaf >= 0) {
      on_leaf(node.leaf);
      continue;
    }
    assert(top + 2 <= MAX_DEPTH);
    stack[top++] = node.right;
    stack[top++] = k + 1;
  }
  return tests;
}

}  // namespace knit
