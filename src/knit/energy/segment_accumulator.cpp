#include "knit/energy/segment_accumulator.hpp"

#include <algorithm>

namespace knit {

void SegmentAccumulator::gather(const Model& model, Eigen::VectorXd& out, double scale) const {
  // one parallel loop over all control points (not one per yarn: a knit has a yarn per
  // row in some samples, and every loop launch is a synchronisation); each chunk finds the
  // yarn of its first control point and walks on
  const std::vector<YarnInfo>& yarns = model.yarns;
  tbb::parallel_for(
      tbb::blocked_range<int>(0, model.num_cp(), 512), [&](const tbb::blocked_range<int>& r) {
        auto yarn = std::upper_bound(yarns.begin(), yarns.end(), r.begin(),
                                     [](int k, const YarnInfo& y) { return k < y.cp_end; });
        for (int k = r.begin(); k < r.end(); ++k) {
          while (k >= yarn->cp_end) ++yarn;
          Eigen::Vector3d sum = Eigen::Vector3d::Zero();
          // local segment i touches local control points i..i+3
          const int local = k - yarn->cp_begin;
          for (int a = 0; a < 4; ++a) {
            const int i = local - a;
            if (i < 0 || i >= yarn->num_seg()) continue;
            sum += m_slots[yarn->seg_begin + i].segment<3>(3 * a);
          }
          out.segment<3>(3 * k) += scale * sum;
        }
      });
}

}  // namespace knit
