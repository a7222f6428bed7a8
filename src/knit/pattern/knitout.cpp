#include "knit/pattern/knitout.hpp"

#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "knit/util/input_file.hpp"

namespace knit {

namespace {

constexpr std::string_view KNITOUT_HEADER = ";!knitout-";

struct Needle {
  char bed = 'f';  ///< 'f' or 'b'
  int index = 0;
  bool operator<(const Needle& o) const { return bed != o.bed ? bed < o.bed : index < o.index; }
};

struct Stitch {
  Needle needle;
  bool purl = false;
  int line = 0;
  std::string instruction;  ///< as written (for messages)
};

class Reader {
 public:
  explicit Reader(const std::string& source) : m_source(source) {}

  [[noreturn]] void fail(int line, const std::string& instruction, const std::string& why) const {
    std::ostringstream msg;
    msg << m_source << ":" << line << ": ";
    if (!instruction.empty()) msg << "'" << instruction << "': ";
    msg << why;
    throw std::invalid_argument(msg.str());
  }

  Needle needle(int line, const std::string& instruction, const std::string& text) const {
    if (text.size() >= 2 && (text[0] == 'f' || text[0] == 'b') && text[1] == 's')
      fail(line, instruction, "sliders (" + text + ") are not supported yet");
    Needle n;
    if (text.empty() || (text[0] != 'f' && text[0] != 'b'))
      fail(line, instruction, "expected a needle such as f12 or b3, got '" + text + "'");
    n.bed = text[0];
    const char* begin = text.data() + 1;
    const char* end = text.data() + text.size();
    const auto res = std::from_chars(begin, end, n.index);
    if (res.ec != std::errc() || res.ptr != end || begin == end)
      fail(line, instruction, "expected a needle such as f12 or b3, got '" + text + "'");
    return n;
  }

  // the carriers of an instruction: exactly one, the same throughout
  void carrier(int line, const std::string& instruction, const std::vector<std::string>& tokens,
               size_t first) {
    if (tokens.size() <= first)
      fail(line, instruction,
           "no carrier given (a stitch without yarn drops the loop: not "
           "supported yet)");
    if (tokens.size() > first + 1)
      fail(line, instruction, "several carriers at once are not supported yet");
    if (m_carrier.empty()) m_carrier = tokens[first];
    if (tokens[first] != m_carrier)
      fail(line, instruction,
           "a second carrier (" + tokens[first] + ", after " + m_carrier +
               ") is not supported yet: one yarn only");
  }

  std::string m_source;
  std::string m_carrier;
};

std::string needle_name(const Needle& n) {
  return std::string(1, n.bed) + std::to_string(n.index);
}

// A needle knitted far fewer times than most of the piece's columns (a typo such as f-3
// for f47, a stray stitch) is named at its first stitch: the row walk would only find the
// rows it shifts, long after it. Pieces of two columns are left to the row walk (which of
// the two is the stray is not to be told).
void check_stray_columns(const Reader& reader, const std::vector<Stitch>& stitches,
                         const std::vector<Needle>& columns,
                         const std::map<Needle, int>& column_of) {
  if (columns.size() < 3) return;
  std::vector<int> height(columns.size(), 0);
  for (const Stitch& s : stitches) ++height[static_cast<size_t>(column_of.at(s.needle))];
  // the height most columns have (a tie: the taller)
  std::map<int, int> how_many;
  for (int h : height) ++how_many[h];
  int usual = 0, most = 0;
  for (const auto& [h, n] : how_many)
    if (n >= most) {
      usual = h;
      most = n;
    }
  for (const Stitch& s : stitches) {
    const int h = height[static_cast<size_t>(column_of.at(s.needle))];
    if (2 * h >= usual) continue;
    reader.fail(s.line, s.instruction,
                "needle " + needle_name(s.needle) + " knits " + std::to_string(h) +
                    (h == 1 ? " stitch" : " stitches") + " in the whole program, and " +
                    std::to_string(most) + " of the piece's " + std::to_string(columns.size()) +
                    " columns knit " + std::to_string(usual) +
                    ": every column is knitted in every row (a mistyped needle?); shaping and "
                    "short rows are not supported yet");
  }
}

}  // namespace

bool is_knitout_path(const std::string& name_or_path) {
  if (name_or_path.size() > 2 && name_or_path.compare(name_or_path.size() - 2, 2, ".k") == 0)
    return true;
  // any other name: a regular file whose first line is knitout's header (a FIFO or device
  // is not opened here; the chart reader refuses it by name)
  std::error_code ec;
  if (!std::filesystem::is_regular_file(name_or_path, ec)) return false;
  std::ifstream in(name_or_path, std::ios::binary);
  char head[16] = {};
  in.read(head, sizeof head);
  std::string_view text(head, static_cast<size_t>(in.gcount()));
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  return text.substr(0, KNITOUT_HEADER.size()) == KNITOUT_HEADER;
}

KnitoutPiece parse_knitout(std::string_view text, const std::string& source_name) {
  Reader reader(source_name);
  std::vector<Stitch> stitches;
  std::map<Needle, bool> cast_on;
  size_t pos = 0;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") pos = 3;
  int line_no = 0;
  bool magic = false;
  while (pos < text.size()) {
    const size_t end = std::min(text.find('\n', pos), text.size());
    std::string line(text.substr(pos, end - pos));
    pos = end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line_no == 1) {
      if (line.rfind(KNITOUT_HEADER, 0) != 0)
        reader.fail(1, "", "not a knitout program: the first line must be ';!knitout-N'");
      magic = true;
      continue;
    }
    const std::string code = line.substr(0, line.find(';'));
    std::istringstream in(code);
    std::vector<std::string> tokens;
    for (std::string t; in >> t;) tokens.push_back(t);
    if (tokens.empty()) continue;
    const std::string& op = tokens[0];
    std::string instruction = tokens[0];
    for (size_t k = 1; k < tokens.size(); ++k) instruction += " " + tokens[k];

    if (op == "in" || op == "inhook" || op == "out" || op == "outhook" || op == "releasehook") {
      reader.carrier(line_no, instruction, tokens, 1);
    } else if (op == "knit" || op == "purl" || op == "tuck" || op == "miss") {
      if (tokens.size() < 3 || (tokens[1] != "+" && tokens[1] != "-"))
        reader.fail(line_no, instruction, "expected '" + op + " +|- NEEDLE CARRIER'");
      const Needle n = reader.needle(line_no, instruction, tokens[2]);
      reader.carrier(line_no, instruction, tokens, 3);
      if (op == "tuck") {
        if (!stitches.empty())
          reader.fail(line_no, instruction,
                      "tucks after the cast-on (tuck stitches) are not supported yet");
        if (cast_on[n]) reader.fail(line_no, instruction, "the needle is already cast on");
        cast_on[n] = true;
      } else if (op != "miss") {
        stitches.push_back({n, op == "purl", line_no, instruction});
      }
    } else if (op == "rack") {
      double r = 0;
      const char* b = tokens.size() > 1 ? tokens[1].data() : nullptr;
      const char* e = b ? b + tokens[1].size() : nullptr;
      if (!b || std::from_chars(b, e, r).ptr != e)
        reader.fail(line_no, instruction, "expected 'rack R'");
      if (r != 0) reader.fail(line_no, instruction, "racking is not supported yet");
    } else if (op == "xfer" || op == "split") {
      reader.fail(line_no, instruction,
                  "transfers (to move loops between beds or make decreases) are not supported yet");
    } else if (op == "drop" || op == "amiss") {
      reader.fail(line_no, instruction, "'" + op + "' is not supported yet");
    } else if (op == "pause" || op == "stitch" || op.rfind("x-", 0) == 0) {
      // machine settings (loop length, speed, pauses): they do not change what is knitted
    } else {
      reader.fail(line_no, instruction, "unknown instruction '" + op + "'");
    }
  }
  if (!magic) reader.fail(1, "", "not a knitout program: the file is empty");
  if (stitches.empty()) reader.fail(line_no, "", "the program knits no stitches");

  // the columns: flat, each needle index on one bed; in the round, the same on both
  std::map<int, std::vector<char>> beds_of;
  for (const Stitch& s : stitches) {
    auto& beds = beds_of[s.needle.index];
    if (std::find(beds.begin(), beds.end(), s.needle.bed) == beds.end())
      beds.push_back(s.needle.bed);
  }
  KnitoutPiece piece;
  for (const auto& [index, beds] : beds_of)
    if (beds.size() == 2) piece.in_the_round = true;
  std::vector<Needle> columns;
  if (!piece.in_the_round) {
    for (const auto& [index, beds] : beds_of) columns.push_back({beds[0], index});
  } else {
    for (const auto& [needle_index, beds] : beds_of) {
      const int index = needle_index;  // clang 14 cannot capture a structured binding
      if (beds.size() != 2) {
        const Stitch& s = *std::find_if(stitches.begin(), stitches.end(),
                                        [&](const Stitch& t) { return t.needle.index == index; });
        reader.fail(s.line, s.instruction,
                    "a tube needs its needles on both beds, but needle " + std::to_string(index) +
                        " is used on one bed only");
      }
      columns.push_back({'f', index});
    }
    for (auto it = beds_of.rbegin(); it != beds_of.rend(); ++it)
      columns.push_back({'b', it->first});
  }
  std::map<Needle, int> column_of;
  for (size_t c = 0; c < columns.size(); ++c) column_of[columns[c]] = static_cast<int>(c);
  const int cols = static_cast<int>(columns.size());
  const auto total = static_cast<int>(stitches.size());
  check_stray_columns(reader, stitches, columns, column_of);
  // every row one whole pass over the columns, in order: the first stitch out of order
  // is the one named
  const int rows = total / cols;
  piece.pattern.rows.assign(rows, std::string(cols, 'k'));
  for (int r = 0; r < rows; ++r) {
    // one pass over every column in order: left to right or back (a round: once around)
    const int first = column_of[stitches[static_cast<size_t>(r * cols)].needle];
    // a flat row, one whole pass, starts at an edge of the piece
    if (!piece.in_the_round && first != 0 && first != cols - 1) {
      const Stitch& s = stitches[static_cast<size_t>(r * cols)];
      reader.fail(s.line, s.instruction,
                  "row " + std::to_string(r) + " starts at needle " + needle_name(s.needle) +
                      ", not at an edge of the piece (" + needle_name(columns.front()) + " or " +
                      needle_name(columns.back()) +
                      "): every row must be one whole pass; shaping and short rows are not "
                      "supported yet");
    }
    int step = 0;
    for (int k = 0; k < cols; ++k) {
      const Stitch& s = stitches[static_cast<size_t>(r * cols + k)];
      const int c = column_of[s.needle];
      // flat: left to right or back; in the round: once around, either way
      if (k == 1)
        step =
            piece.in_the_round ? ((c - first + cols) % cols == 1 ? 1 : -1) : (c > first ? 1 : -1);
      const int expected =
          piece.in_the_round ? ((first + step * k) % cols + cols) % cols : first + step * k;
      if (k > 0 && c != expected)
        reader.fail(
            s.line, s.instruction,
            "row " + std::to_string(r) + " does not go over the columns in order " +
                "(expected needle " +
                needle_name(columns[static_cast<size_t>(std::clamp(expected, 0, cols - 1))]) +
                "): every row must be one whole pass; shaping and short rows are not "
                "supported yet");
      const bool back = s.needle.bed == 'b';
      const bool knit_front = piece.in_the_round ? !s.purl : (back == s.purl);
      piece.pattern.rows[r][c] = knit_front ? 'k' : 'p';
    }
  }
  if (total % cols != 0) {
    const Stitch& s = stitches[static_cast<size_t>(total - total % cols)];
    reader.fail(s.line, s.instruction,
                "the last row has " + std::to_string(total % cols) + " of the piece's " +
                    std::to_string(cols) +
                    " stitches: shaping and short rows are not supported yet");
  }
  return piece;
}

KnitoutPiece load_knitout(const std::string& path) {
  std::string text;
  try {
    text = read_input_file(path, MAX_CHART_BYTES, "knitout program");
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(e.what());
  }
  return parse_knitout(text, path);
}

}  // namespace knit
