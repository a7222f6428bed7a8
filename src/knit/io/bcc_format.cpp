// Reader for Cem Yuksel's BCC binary curve collection. Header (64 bytes, little-endian):
//   char sign[3] = "BCC" | u8 byte_count = 0x44 (4-byte integers and floats)
//   char curve_type[2] ("PL" polyline, "C0" uniform Catmull-Rom) | u8 dimensions = 3
//   u8 up_dimension | u64 curve_count | u64 total_point_count | char file_info[40]
// then per curve: int32 point count (negative: closed curve) and float xyz per point.
#include <cmath>
#include <cstdlib>

#include "knit/io/bcc.hpp"
#include "knit/io/import.hpp"
#include "knit/util/byte_reader.hpp"

namespace knit {
namespace {

// uniform Catmull-Rom span between p1 and p2 at t ∈ [0,1]
Eigen::Vector3d catmull_rom(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                            const Eigen::Vector3d& p2, const Eigen::Vector3d& p3, double t) {
  const double t2 = t * t, t3 = t2 * t;
  return 0.5 * (2 * p1 + (p2 - p0) * t + (2 * p0 - 5 * p1 + 4 * p2 - p3) * t2 +
                (3 * p1 - p0 - 3 * p2 + p3) * t3);
}

// samples a Catmull-Rom curve through `cp` into a polyline, `per_span` points per span.
// Open curves get phantom end points reflected through the ends (p₋₁ = 2p₀ − p₁), so the
// curve starts and ends at the first and last control points.
Eigen::Matrix3Xd sample_catmull_rom(const Eigen::Matrix3Xd& cp, bool closed, int per_span) {
  const int n = static_cast<int>(cp.cols());
  auto at = [&](int i) -> Eigen::Vector3d {
    if (closed) return cp.col(((i % n) + n) % n);
    if (i < 0) return 2 * cp.col(0) - cp.col(1);
    if (i >= n) return 2 * cp.col(n - 1) - cp.col(n - 2);
    return cp.col(i);
  };
  const int spans = closed ? n : n - 1;
  Eigen::Matrix3Xd out(3, spans * per_span + 1);
  for (int s = 0; s < spans; ++s)
    for (int k = 0; k < per_span; ++k)
      out.col(s * per_span + k) =
          catmull_rom(at(s - 1), at(s), at(s + 1), at(s + 2), static_cast<double>(k) / per_span);
  out.col(spans * per_span) = closed ? at(0) : at(n - 1);
  return out;
}

}  // namespace

std::vector<RawYarn> parse_bcc(std::string_view data, const std::string& name) {
  detail::ByteReader r(data, name);
  r.set_context("header");
  const std::string_view sign = r.bytes(3, "signature");
  if (sign != "BCC") r.fail_at(0, "signature is not 'BCC' (not a BCC file)");
  const auto byte_count = r.get<uint8_t>("byte count");
  if (byte_count != 0x44)
    r.fail_at(3, "byte count is " + std::to_string(byte_count) +
                     ", only 0x44 (4-byte integers and floats) is supported");
  const std::string type(r.bytes(2, "curve type"));
  if (type != "PL" && type != "C0")
    r.fail_at(
        4, "curve type '" + detail::printable_tag(type) + "' is not supported (expected PL or C0)");
  const auto dims = r.get<uint8_t>("dimensions");
  if (dims != 3) r.fail_at(6, "dimensions is " + std::to_string(dims) + ", expected 3");
  r.get<uint8_t>("up dimension");
  const auto curve_count = r.get<uint64_t>("curve count");
  const auto total_points = r.get<uint64_t>("total point count");
  r.bytes(40, "file info");
  if (curve_count == 0) r.fail_at(8, "no curves");
  if (curve_count > r.remaining() / 4)
    r.fail_at(8, "curve count " + std::to_string(curve_count) + " exceeds the file size");
  if (total_points > r.remaining() / 12)
    r.fail_at(16, "total point count " + std::to_string(total_points) + " exceeds the file size");

  std::vector<RawYarn> out;
  uint64_t seen = 0;
  for (uint64_t c = 0; c < curve_count; ++c) {
    r.set_context("curve " + std::to_string(c));
    const size_t at = r.pos();
    const int64_t count = r.get<int32_t>("point count");
    const bool closed = count < 0;
    const int64_t n = std::llabs(count);
    if (n < 2) r.fail_at(at, "has " + std::to_string(n) + " points (need at least 2)");
    if (static_cast<uint64_t>(n) > r.remaining() / 12)
      r.fail_at(at, "claims " + std::to_string(n) + " points, more than the file holds");
    Eigen::Matrix3Xd cp(3, n);
    for (int64_t k = 0; k < n; ++k)
      for (int d = 0; d < 3; ++d) {
        const size_t pat = r.pos();
        const float v = r.get<float>("point coordinates");
        if (!std::isfinite(v))
          r.fail_at(pat, "point " + std::to_string(k) + " has a non-finite coordinate");
        cp(d, k) = v;
      }
    seen += static_cast<uint64_t>(n);
    RawYarn yarn;
    if (type == "PL") {
      if (closed) {
        yarn.points.resize(3, n + 1);
        yarn.points << cp, cp.col(0);
      } else {
        yarn.points = std::move(cp);
      }
    } else {
      yarn.points = sample_catmull_rom(cp, closed, 8);
    }
    out.push_back(std::move(yarn));
  }
  r.set_context("");
  if (seen != total_points)
    r.fail_at(16, "header says " + std::to_string(total_points) + " points, curves hold " +
                      std::to_string(seen));
  if (r.remaining() != 0)
    r.fail("unexpected " + std::to_string(r.remaining()) + " bytes after the last curve");
  return out;
}

std::string bcc_polylines(const std::vector<Eigen::Matrix3Xd>& curves, const std::string& info) {
  std::string out;
  auto put = [&out](const auto& v) {
    char buf[sizeof(v)];
    std::memcpy(buf, &v, sizeof(v));
    out.append(buf, sizeof(v));
  };
  uint64_t total = 0;
  for (const auto& c : curves) total += static_cast<uint64_t>(c.cols());
  out.append("BCC");
  put(uint8_t{0x44});
  out.append("PL");
  put(uint8_t{3});
  put(uint8_t{2});  // up dimension: z
  put(static_cast<uint64_t>(curves.size()));
  put(total);
  char file_info[40] = {};
  std::memcpy(file_info, info.data(), std::min<size_t>(info.size(), sizeof(file_info) - 1));
  out.append(file_info, sizeof(file_info));
  for (const auto& c : curves) {
    put(static_cast<int32_t>(c.cols()));
    for (Eigen::Index k = 0; k < c.cols(); ++k)
      for (int d = 0; d < 3; ++d) put(static_cast<float>(c(d, k)));
  }
  return out;
}

}  // namespace knit
