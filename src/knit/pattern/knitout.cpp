#include "knit/pattern/knitout.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <vector>

#include "knit/graph/knitout_machine.hpp"

namespace knit {

namespace {

constexpr std::string_view KNITOUT_HEADER = ";!knitout-";

using graph::KnitGraph;
using graph::Loop;
using graph::LoopId;

// the text of line `n` (1-based) of `text`, trimmed
std::string line_text(std::string_view text, int n) {
  size_t begin = 0;
  for (int k = 1; k < n && begin != std::string_view::npos; ++k) {
    begin = text.find('\n', begin);
    if (begin != std::string_view::npos) ++begin;
  }
  if (begin == std::string_view::npos || begin > text.size()) return "";
  size_t end = text.find('\n', begin);
  std::string_view line = text.substr(begin, end == std::string_view::npos ? end : end - begin);
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t'))
    line.remove_suffix(1);
  while (!line.empty() && (line.front() == ' ' || line.front() == '\t')) line.remove_prefix(1);
  return std::string(line);
}

// Reads the rectangular sheet the generator lays out of a program's knit graph (see
// knitout.hpp), or refuses naming the line.
class SheetReader {
 public:
  SheetReader(const KnitGraph& g, std::string_view text, const std::string& source, int last_line)
      : m_g(g), m_text(text), m_source(source), m_last_line(last_line) {}

  [[noreturn]] void fail(int line, const std::string& what) const {
    if (line <= 0) throw std::invalid_argument(m_source + ": " + what);
    throw std::invalid_argument(m_source + ":" + std::to_string(line) + ": '" +
                                line_text(m_text, line) + "': " + what);
  }

  KnitoutPiece read() {
    const KnitGraph& g = m_g;
    // the cast-on (not laid): loops tucked onto empty needles before the first stitch, or
    // knit onto them in several passes (mark_knit_cast_on)
    const size_t n = g.num_loops();
    std::vector<int> row(n, -1), wale(n, -1);
    std::vector<char> cast_on(n, 0);
    bool stitched = false;
    mark_knit_cast_on(cast_on);
    for (LoopId id = 0; id < n; ++id) {
      if (cast_on[id]) continue;
      const Loop& l = g.loop(id);
      const auto parents = g.parents(id);
      if (l.kind == graph::LoopKind::TUCK)
        fail(l.line,
             "a tuck beside the loops a needle holds: tucks after the cast-on need the "
             "knit graph's own layout, not built yet");
      if (l.kind == graph::LoopKind::SPLIT)
        fail(l.line,
             "a split: transfers that knit need the knit graph's own layout, not built yet");
      if (l.kind == graph::LoopKind::NEW && l.tucked && !stitched) {
        cast_on[id] = 1;
        continue;
      }
      if (!stitched) m_edge_cast_on = edge_cast_on_loop(id, cast_on);
      stitched = true;
      if (parents.size() > 1)
        fail(l.line, "a decrease (" + std::to_string(parents.size()) +
                         " loops pulled through at once): shaping needs the knit graph's own "
                         "layout, not built yet");
      if (!parents.empty() && parents[0] == m_edge_cast_on && cast_on[m_edge_cast_on]) {
        // the cast-on's last loop, at the edge the first row starts from, which that row
        // passes by: laid as the first stitch of its column's first row, the yarn turning
        // there
        cast_on[m_edge_cast_on] = 0;
        row[m_edge_cast_on] = 0;
        wale[m_edge_cast_on] = static_cast<int>(m_wales.size());
        m_wales.push_back(m_edge_cast_on);
      }
      if (parents.empty() || cast_on[parents[0]]) {
        // a new column: only in the first row of stitches
        if (m_first_pass < 0) m_first_pass = l.pass;
        if (l.pass == m_first_pass) m_first_beds |= graph::is_front_side(l.bed) ? 1 : 2;
        if (l.pass != m_first_pass && !m_round_second(l)) {
          // (named after the first row's needles are checked: a mistyped needle there
          // leaves a column to start late)
          check_first_row_needles();
          fail(l.line, std::string("a new column (a loop on ") +
                           (parents.empty() ? "an empty needle" : "a cast-on loop") +
                           ") after the first row: a column that starts a pass late, "
                           "increases, yarn-overs and shaping need the knit graph's own layout, "
                           "not built yet");
        }
        row[id] = 0;
        wale[id] = static_cast<int>(m_wales.size());
        m_wales.push_back(id);
      } else {
        const LoopId p = parents[0];
        row[id] = row[p] + 1;
        wale[id] = wale[p];
      }
    }
    if (m_wales.empty()) fail(m_last_line, "the program knits no stitches");
    if (!g.crossings().empty())
      fail(g.crossings().front().line,
           "racking carries loops across each other (a cable or twist): crossings need the knit "
           "graph's own layout, not built yet");

    // the first row's passes: one (a flat piece) or a front and a back pass (a tube)
    KnitoutPiece piece;
    const Loop& first = g.loop(m_wales.front());
    piece.in_the_round = m_second_pass >= 0;
    std::vector<LoopId> front, back;  // the first row's loops by side (a tube's halves)
    for (LoopId w : m_wales)
      (g.loop(w).pass == first.pass || w == m_edge_cast_on ? front : back).push_back(w);
    auto by_needle = [&](LoopId a, LoopId b) { return g.loop(a).needle < g.loop(b).needle; };
    std::sort(front.begin(), front.end(), by_needle);
    std::sort(back.begin(), back.end(), by_needle);
    if (piece.in_the_round) {
      // (the first pass is on one bed and the second on the other: m_round_second)
      if (!graph::is_front_side(first.bed)) std::swap(front, back);
      // around the tube: the front needles left to right, then the back ones right to left
      std::reverse(back.begin(), back.end());
    }
    std::vector<int> column(m_wales.size());
    int cols = 0;
    for (const auto* half : {&front, &back})
      for (LoopId w : *half) column[wale[w]] = cols++;

    // rows: every column once per row, the rows one after the other
    int rows = 0;
    for (LoopId id = 0; id < n; ++id)
      if (!cast_on[id]) rows = std::max(rows, row[id] + 1);
    // the loops of each row, in the order made (a row that is not full is refused before
    // anything of the size rows × columns is made)
    std::vector<std::vector<LoopId>> in_row(rows);
    for (LoopId id = 0; id < n; ++id)
      if (!cast_on[id]) in_row[row[id]].push_back(id);
    const int per_row = piece.in_the_round ? 2 : 1;
    int last_pass = -1, last_dir = 0;
    // the yarns (a graph's yarn → the piece's, in the order they first knit a row) and the
    // last row and direction of each
    std::map<int, int> yarn_of;
    std::vector<std::pair<int, int>> yarn_last;  // (row, direction)
    std::vector<int> row_yarn(rows);
    std::vector<char> row_leftward(rows);
    for (int r = 0; r < rows; ++r) {
      const std::vector<LoopId>& order = in_row[r];
      if (static_cast<int>(order.size()) != cols)
        fail(g.loop(order.front()).line,
             "row " + std::to_string(r) + " has " + std::to_string(order.size()) +
                 " of the piece's " + std::to_string(cols) +
                 " stitches: shaping and short rows need the knit graph's own layout, not built "
                 "yet");
      // one yarn knits the row (stripes: a yarn is carried up the edge to its next row)
      const int yarn = g.loop(order.front()).yarn;
      for (LoopId id : order)
        if (g.loop(id).yarn != yarn)
          fail(g.loop(id).line, "row " + std::to_string(r) + " is knit by two yarns (carriers " +
                                    g.yarns()[yarn].carrier + " and " +
                                    g.yarns()[g.loop(id).yarn].carrier +
                                    "): intarsia needs the knit graph's own layout, not built yet");
      std::map<int, int> passes;
      for (LoopId id : order)
        if (id != m_edge_cast_on) ++passes[g.loop(id).pass];
      if (static_cast<int>(passes.size()) != per_row)
        fail(g.loop(order.front()).line,
             "row " + std::to_string(r) + " is knit in " + std::to_string(passes.size()) +
                 " passes, not " + std::to_string(per_row) +
                 ": short rows and kickbacks need the knit graph's own layout, not built yet");
      if (r > 0 && passes.begin()->first <= last_pass)
        fail(g.loop(order.front()).line,
             "row " + std::to_string(r) + " begins before row " + std::to_string(r - 1) + " ends");
      last_pass = passes.rbegin()->first;
      if (!yarn_of.count(yarn)) {
        if (piece.in_the_round && !yarn_of.empty())
          fail(g.loop(order.front()).line,
               "round " + std::to_string(r) + " is knit by a second yarn (carrier " +
                   g.yarns()[yarn].carrier + "): stripes in the round are not laid yet");
        yarn_of[yarn] = static_cast<int>(yarn_last.size());
        yarn_last.push_back({-1, 0});
      }
      const int py = yarn_of[yarn];
      row_yarn[r] = py;
      // the yarn goes along the columns in order: around the tube, or to and fro, turning
      // at the edges (the first row from either edge)
      int dir = 0;
      for (size_t k = 1; k < order.size(); ++k) {
        const int c0 = column[wale[order[k - 1]]], c1 = column[wale[order[k]]];
        const int step = piece.in_the_round ? ((c1 - c0 + cols + 1) % cols) - 1 : c1 - c0;
        if (std::abs(step) != 1 || (dir != 0 && step != dir))
          fail(g.loop(order[k]).line,
               "row " + std::to_string(r) +
                   " does not go over the columns in order: every row must be one whole pass "
                   "along them");
        dir = step;
        // neighbouring columns on neighbouring needles (on a tube, along each bed): the
        // generator lays no float across empty needles. Named at the loop out of line
        // with both its neighbours (a mistyped needle), else at the later one.
        check_neighbours(order, k, r, piece.in_the_round);
      }
      const auto [yarn_row, yarn_dir] = yarn_last[py];
      if (!piece.in_the_round && yarn_row >= 0 && dir != 0 && dir == yarn_dir)
        fail(g.loop(order.front()).line,
             "row " + std::to_string(r) + " starts at the edge where row " +
                 std::to_string(yarn_row) + " started" +
                 (yarn_row == r - 1 ? std::string()
                                    : " (both knit by carrier " + g.yarns()[yarn].carrier + ")") +
                 ": the yarn would float back along the row");
      yarn_last[py] = {r, dir};
      // (a row of one stitch goes the way its carriage did)
      row_leftward[r] = (dir != 0 ? dir : static_cast<int>(g.loop(order.front()).direction)) < 0;
      if (piece.in_the_round && r > 0 && dir != 0 && last_dir != 0 && dir != last_dir)
        fail(g.loop(order.front()).line,
             "round " + std::to_string(r) + " goes around the other way");
      if (dir != 0) last_dir = dir;
      if (r == 0) piece.pattern.first_row_leftward = dir < 0;
    }
    if (yarn_last.size() > 1) {
      piece.pattern.row_yarn = row_yarn;
      piece.pattern.row_leftward = row_leftward;
    }
    piece.pattern.rows.assign(rows, std::string(cols, 'k'));
    for (int r = 0; r < rows; ++r)
      for (LoopId id : in_row[r]) {
        const Loop& l = g.loop(id);
        bool knit = l.face == graph::Face::KNIT;
        // a tube is seen from outside: the back bed's loops from behind
        if (piece.in_the_round && !graph::is_front_side(l.bed)) knit = !knit;
        piece.pattern.rows[r][column[wale[id]]] = knit ? 'k' : 'p';
      }
    // (every loop below the top row is held by the one above it: a dropped one, which
    // would ladder, leaves its column a row short, refused above)
    return piece;
  }

 private:
  // A cast-on knit onto empty needles in several passes (machines cast on alternate needles
  // in two passes, then knit them all): every loop before the first one knit through
  // another is knit on an empty needle, one per needle, in more than one pass — but for a
  // tube's first round (a pass on one bed, then one on the other). Marks them cast-on.
  void mark_knit_cast_on(std::vector<char>& cast_on) const {
    std::map<int, int> beds;  // pass → beds its loops are on (1 front, 2 back)
    LoopId end = 0;
    for (; end < m_g.num_loops(); ++end) {
      const Loop& l = m_g.loop(end);
      if (!m_g.parents(end).empty() || l.kind != graph::LoopKind::NEW) break;
      beds[l.pass] |= graph::is_front_side(l.bed) ? 1 : 2;
    }
    // (loops tucked on empty needles are the cast-on anyway; a knit cast-on is all knit,
    // one loop per needle)
    std::set<std::pair<int, int>> needles;
    for (LoopId id = 0; id < end; ++id) {
      const Loop& l = m_g.loop(id);
      if (l.tucked || !needles.insert({static_cast<int>(l.bed), l.needle}).second) return;
    }
    if (beds.size() < 2) return;
    if (beds.size() == 2 && beds.begin()->second != 3 &&
        beds.begin()->second + beds.rbegin()->second == 3)
      return;  // a tube's first round
    for (LoopId id = 0; id < end; ++id) cast_on[id] = 1;
  }

  // The cast-on loop a tucked cast-on's last tuck left at the edge the first row of stitches
  // starts from, beside that row's first needle, when that row knits away from it without
  // knitting it (a machine's alternate-bed cast-on for a rib: the yarn turns there): its
  // column's first stitch comes a pass late, through this loop, which is laid as that
  // column's first-row stitch. `first` is the first stitch knit. NO_LOOP when there is none.
  LoopId edge_cast_on_loop(LoopId first, const std::vector<char>& cast_on) const {
    if (first == 0 || !cast_on[first - 1] || !m_g.loop(first - 1).tucked) return graph::NO_LOOP;
    const Loop &edge = m_g.loop(first - 1), &knit = m_g.loop(first);
    const int away = knit.needle - edge.needle;
    if (edge.yarn != knit.yarn || std::abs(away) != 1) return graph::NO_LOOP;
    if (static_cast<int>(knit.direction) != away) return graph::NO_LOOP;
    return first - 1;
  }

  // Neighbouring columns on neighbouring needles (on a tube, along each bed): the generator
  // lays no float across empty needles. Checks loops order[k − 1] and order[k] of row `r`
  // (in the order made), naming the loop out of line with both its neighbours (a mistyped
  // needle), else the later one.
  void check_neighbours(const std::vector<LoopId>& order, size_t k, int r, bool round) const {
    const Loop &la = m_g.loop(order[k - 1]), &lb = m_g.loop(order[k]);
    const bool same_side = graph::is_front_side(la.bed) == graph::is_front_side(lb.bed);
    if ((!same_side && round) || std::abs(lb.needle - la.needle) == 1) return;
    const bool first_odd =
        k == 1 && (order.size() < 3 || std::abs(m_g.loop(order[2]).needle - lb.needle) == 1);
    const Loop& odd = first_odd ? la : lb;
    const Loop& other = first_odd ? lb : la;
    fail(odd.line, "needle " + graph::needle_name(odd.bed, odd.needle) + " is not beside " +
                       graph::needle_name(other.bed, other.needle) + " (line " +
                       std::to_string(other.line) + "), its neighbour in row " + std::to_string(r) +
                       ": the generator lays stitches on neighbouring needles");
  }
  // the first row's first pass, as far as it is read
  void check_first_row_needles() const {
    std::vector<LoopId> first;
    for (LoopId w : m_wales)
      if (m_g.loop(w).pass == m_first_pass) first.push_back(w);
    for (size_t k = 1; k < first.size(); ++k) check_neighbours(first, k, 0, false);
  }

  // whether `l` is in the second pass of a tube's first round (a pass on the other bed right
  // after the first one, making new columns)
  bool m_round_second(const Loop& l) {
    const Loop& first = m_g.loop(m_wales.front());
    // (a first pass on both beds is a flat piece: a rib)
    if (m_second_pass < 0 && l.pass == first.pass + 1 && m_first_beds != 3 &&
        graph::is_front_side(l.bed) != graph::is_front_side(first.bed))
      m_second_pass = l.pass;
    return l.pass == m_second_pass;
  }

  const KnitGraph& m_g;
  std::string_view m_text;
  const std::string& m_source;
  int m_last_line = 0;
  std::vector<LoopId> m_wales;  // the first loop of each column
  int m_first_pass = -1, m_second_pass = -1;
  LoopId m_edge_cast_on = graph::NO_LOOP;  // see edge_cast_on_loop
  int m_first_beds = 0;  // the beds of the first pass's loops: 1 front, 2 back, 3 both
};

}  // namespace

bool is_knitout_path(const std::string& name_or_path) {
  if (name_or_path.size() > 2 && name_or_path.compare(name_or_path.size() - 2, 2, ".k") == 0)
    return true;
  if (name_or_path.size() > 8 && name_or_path.compare(name_or_path.size() - 8, 8, ".knitout") == 0)
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

KnitoutPiece knitout_sheet(const graph::KnitoutResult& result, std::string_view text,
                           const std::string& source_name) {
  return SheetReader(result.graph, text, source_name, result.lines).read();
}

KnitoutPiece parse_knitout(std::string_view text, const std::string& source_name) {
  return knitout_sheet(graph::run_knitout(text, source_name), text, source_name);
}

KnitoutPiece load_knitout(const std::string& path) {
  return parse_knitout(graph::read_knitout_text(path), path);
}

}  // namespace knit
