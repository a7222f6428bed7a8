#include "knit/energy/segment_accumulator.hpp"

namespace knit {

void SegmentAccumulator::gather(const Model& model, Eigen::VectorXd& out, double scale) const {
  for (const YarnInfo& yarn : model.yarns) {
    tbb::parallel_for(
        tbb::blocked_range<int>(yarn.cp_begin, yarn.cp_end, 256),
        [&](const tbb::blocked_range<int>& r) {
          for (int k = r.begin(); k < r.end(); ++k) {
            Eigen::Vector3d sum = Eigen::Vector3d::Zero();
            // local segment i touches local control points i..i+3
            const int local = k - yarn.cp_begin;
            for (int a = 0; a < 4; ++a) {
              const int i = local - a;
              if (i < 0 || i >= yarn.num_seg()) continue;
              sum += m_slots[yarn.seg_begin + i].segment<3>(3 * a);
            }
            out.segment<3>(3 * k) += scale * sum;
          }
        });
  }
}

}  // namespace knit
