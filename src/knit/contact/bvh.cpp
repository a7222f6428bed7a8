#include "knit/contact/bvh.hpp"

#include <stdexcept>

namespace knit {

void Bvh::build(const std::vector<Aabb>& leaves) {
  m_nodes.clear();
  m_num_leaves = static_cast<int>(leaves.size());
  if (leaves.empty()) return;
  m_nodes.reserve(2 * leaves.size() - 1);
  std::vector<int> order(leaves.size());
  std::vector<Eigen::Vector3d> centres(leaves.size());
  for (size_t k = 0; k < leaves.size(); ++k) {
    order[k] = static_cast<int>(k);
    centres[k] = 0.5 * (leaves[k].lo + leaves[k].hi);
  }
  build_range(order, centres, 0, m_num_leaves);
  refit(leaves);
}

int Bvh::build_range(std::vector<int>& order, std::vector<Eigen::Vector3d>& centres, int begin,
                     int end) {
  const int index = static_cast<int>(m_nodes.size());
  m_nodes.emplace_back();
  if (end - begin == 1) {
    m_nodes[index].leaf = order[begin];
    m_nodes[index].max_leaf = order[begin];
    return index;
  }
  // split at the median of the box centres along their longest extent; ties broken by
  // leaf index so the topology is a pure function of the input
  Aabb spread;
  for (int k = begin; k < end; ++k) spread.extend(centres[order[k]]);
  int axis = 0;
  (spread.hi - spread.lo).maxCoeff(&axis);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](int a, int b) {
                     const double ca = centres[a][axis], cb = centres[b][axis];
                     return ca < cb || (ca == cb && a < b);
                   });
  build_range(order, centres, begin, mid);
  const int right = build_range(order, centres, mid, end);
  m_nodes[index].right = right;
  m_nodes[index].max_leaf = std::max(m_nodes[index + 1].max_leaf, m_nodes[right].max_leaf);
  return index;
}

void Bvh::refit(const std::vector<Aabb>& leaves) {
  if (static_cast<int>(leaves.size()) != m_num_leaves)
    throw std::logic_error("Bvh::refit: the number of leaves changed since the build");
  // children come after their parent: sweep backwards
  for (int k = static_cast<int>(m_nodes.size()) - 1; k >= 0; --k) {
    Node& node = m_nodes[k];
    if (node.leaf >= 0) {
      node.box = leaves[node.leaf];
    } else {
      node.box = m_nodes[k + 1].box;
      node.box.extend(m_nodes[node.right].box);
    }
  }
}

}  // namespace knit
