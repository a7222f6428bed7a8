// Reader for the textiles-lab smobj `.yarns` format: a sequence of chunks, each a 4-byte
// tag and a uint32 byte size (little-endian):
//   f3..  float x, y, z per point
//   src.  uint32 per point (knitout source line; ignored)
//   yarn  per yarn: uint32 point_begin, uint32 point_end (exclusive), float radius, u8 rgba
//   strs  characters (unit names; ignored)
//   unit  per unit: uint32 name_begin, uint32 name_end, float length (ignored)
//   chk.  per checkpoint: uint32 point, float length, uint32 unit (ignored)
// Unknown chunks with printable tags are skipped (forward compatibility).
#include <cmath>
#include <map>

#include "knit/io/import.hpp"
#include "knit/util/byte_reader.hpp"

namespace knit {

std::vector<RawYarn> parse_yarns_file(std::string_view data, const std::string& name) {
  detail::ByteReader r(data, name);
  if (data.empty()) r.fail("empty file (expected .yarns chunks)");
  struct Chunk {
    size_t offset = 0;  // of the payload
    uint32_t size = 0;
  };
  std::map<std::string, Chunk> chunks;
  static const std::map<std::string, uint32_t> record_size = {
      {"f3..", 12}, {"src.", 4}, {"yarn", 16}, {"strs", 1}, {"unit", 12}, {"chk.", 12}};
  while (r.remaining() > 0) {
    const size_t at = r.pos();
    r.set_context("chunk header");
    const std::string tag(r.bytes(4, "chunk tag"));
    const std::string shown = "chunk '" + detail::printable_tag(tag) + "'";
    r.set_context(shown);
    const auto size = r.get<uint32_t>("chunk size");
    if (size > r.remaining())
      r.fail_at(at, "chunk claims " + std::to_string(size) + " bytes but only " +
                        std::to_string(r.remaining()) + " remain (truncated?)");
    const auto known = record_size.find(tag);
    if (known == record_size.end()) {
      for (unsigned char c : tag)
        if (c < 32 || c >= 127) r.fail_at(at, "not a chunk tag (corrupt file or not .yarns)");
    } else {
      if (size % known->second != 0)
        r.fail_at(at, "size " + std::to_string(size) + " is not a multiple of the " +
                          std::to_string(known->second) + "-byte record");
      if (chunks.count(tag)) r.fail_at(at, "appears twice");
      chunks[tag] = Chunk{r.pos(), size};
    }
    r.seek(r.pos() + size);
  }
  r.set_context("");
  for (const char* required : {"f3..", "yarn"})
    if (!chunks.count(required))
      r.fail_at(data.size(), std::string("no '") + required + "' chunk (not a .yarns file?)");

  // points
  const Chunk pc = chunks["f3.."];
  const size_t npoints = pc.size / 12;
  r.seek(pc.offset);
  r.set_context("chunk 'f3..'");
  Eigen::Matrix3Xd points(3, static_cast<Eigen::Index>(npoints));
  for (size_t k = 0; k < npoints; ++k)
    for (int c = 0; c < 3; ++c) {
      const size_t at = r.pos();
      const float v = r.get<float>("point coordinates");
      if (!std::isfinite(v))
        r.fail_at(at, "point " + std::to_string(k) + " has a non-finite coordinate");
      points(c, static_cast<Eigen::Index>(k)) = v;
    }
  if (chunks.count("src.") && chunks["src."].size / 4 != npoints) {
    r.set_context("chunk 'src.'");
    r.fail_at(chunks["src."].offset - 8, "has " + std::to_string(chunks["src."].size / 4) +
                                             " entries for " + std::to_string(npoints) + " points");
  }

  // yarns
  const Chunk yc = chunks["yarn"];
  r.seek(yc.offset);
  r.set_context("chunk 'yarn'");
  const size_t nyarn = yc.size / 16;
  if (nyarn == 0) r.fail_at(yc.offset - 8, "no yarns");
  std::vector<RawYarn> out;
  for (size_t y = 0; y < nyarn; ++y) {
    const size_t at = r.pos();
    const auto begin = r.get<uint32_t>("yarn point_begin");
    const auto end = r.get<uint32_t>("yarn point_end");
    const float radius = r.get<float>("yarn radius");
    r.bytes(4, "yarn colour");
    const std::string which = "yarn " + std::to_string(y);
    if (begin >= end)
      r.fail_at(at, which + " has an empty or reversed point range [" + std::to_string(begin) +
                        ", " + std::to_string(end) + ")");
    if (end > npoints)
      r.fail_at(at, which + " has point range [" + std::to_string(begin) + ", " +
                        std::to_string(end) + ") outside the " + std::to_string(npoints) +
                        " points of chunk 'f3..'");
    if (end - begin < 2) r.fail_at(at, which + " has fewer than 2 points");
    if (!(radius > 0) || !std::isfinite(radius))
      r.fail_at(at + 8, which + " has radius " + std::to_string(static_cast<double>(radius)) +
                            " (expected a finite value > 0)");
    RawYarn yarn;
    yarn.points = points.middleCols(begin, end - begin);
    yarn.radius = radius;
    out.push_back(std::move(yarn));
  }
  return out;
}

}  // namespace knit
