#include "knit/graph/chart.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>

namespace knit::graph {

namespace {

enum class Op {
  KNIT,      // pulled through `take` stitches (k, p, decreases, tbl)
  NEW,       // yo
  M1,        // from the bar
  SLIP,      // carried up, the yarn floats past
  TUCK,      // carried up with a tuck loop on it
  BIND_OFF,  // knit, then passed over by the next
  UNWORKED,  // '-'
  WRAP,      // w&t
  DOUBLE,    // ds
  NONE,      // '.'
  CABLE
};

// what a symbol does, as seen from the right side
struct Spec {
  Op op = Op::KNIT;
  int take = 1;
  Face face = Face::KNIT;
  std::array<int, 3> order{};  // parents: indices into the taken stitches (left to right)
  int parents = 0;             // entries of `order` used
  bool tbl = false;
  bool wyif = false;       // slip: the float in front (right side)
  bool leans_left = true;  // m1
  // cables: `front` stitches pass in front of `back` ones; front_left: the front group
  // ends on the left (a left cross, F), else on the right (B)
  int front = 0, back = 0;
  bool front_left = true;
  Face front_face = Face::KNIT, back_face = Face::KNIT;
  int width() const { return op == Op::CABLE ? front + back : 1; }
};

struct Cell {
  std::string_view token;  // as written (in the chart's text)
  std::string sym;         // normalised (short: no allocation)
  int text_col = 0;        // 1-based
  int index = 0;           // 1-based in its line
  int column = 0;          // grid column of its left edge, 1-based
  std::string_view yarn;   // in the chart's text, or the default yarn's name
  Spec spec;
};

struct Row {
  int line = 0;
  std::vector<Cell> cells;  // left to right as seen from the front
  int width = 0;
};

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r'))
    s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r'))
    s.remove_suffix(1);
  return s;
}

Face flip(Face f) {
  return f == Face::KNIT ? Face::PURL : Face::KNIT;
}

bool valid_yarn_name(std::string_view s) {
  if (s.empty() || s.size() > 32) return false;
  for (char c : s)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

// reads digits at s[p...]; returns -1 when there are none (or too many)
int read_int(std::string_view s, std::size_t& p) {
  const std::size_t start = p;
  int v = 0;
  while (p < s.size() && std::isdigit(static_cast<unsigned char>(s[p]))) {
    v = v * 10 + (s[p] - '0');
    ++p;
    if (p - start > 4) return -1;
  }
  return p == start ? -1 : v;
}

// cables and twists: c4f, c6b, c2/1f, t2r, t1/1l, 2/2lc, 2/1rpc; `ok` false when `s` is
// none of these; throws (by returning a message) on a width out of range
bool cable_spec(const std::string& s, Spec& out, std::string& problem) {
  if (s.size() < 3) return false;
  Spec sp;
  sp.op = Op::CABLE;
  std::size_t p = 0;
  bool twist = false;
  int a = -1, b = -1;
  std::string tail;
  if (s[0] == 'c' || s[0] == 't') {
    twist = s[0] == 't';
    p = 1;
    a = read_int(s, p);
    if (a < 0) return false;
    if (p < s.size() && s[p] == '/') {
      ++p;
      b = read_int(s, p);
      if (b < 0) return false;
    }
    tail = s.substr(p);
    if (twist ? (tail != "r" && tail != "l") : (tail != "f" && tail != "b")) return false;
    sp.front_left = tail == "f" || tail == "l";
    if (b < 0) {
      if (a % 2 != 0 || a < 2) {
        problem = "a cable or twist of " + std::to_string(a) +
                  " stitches without a split (write X/Y, e.g. " + std::string(1, s[0]) + "2/1" +
                  tail + "): expected an even count, at least 2";
        return true;
      }
      b = a / 2;
      a = a / 2;
    }
  } else if (std::isdigit(static_cast<unsigned char>(s[0]))) {
    a = read_int(s, p);
    if (a < 0 || p >= s.size() || s[p] != '/') return false;
    ++p;
    b = read_int(s, p);
    if (b < 0) return false;
    tail = s.substr(p);
    if (tail == "lc" || tail == "rc") {
      twist = false;
    } else if (tail == "lpc" || tail == "rpc") {
      twist = true;
    } else {
      return false;
    }
    sp.front_left = tail[0] == 'l';
  } else {
    return false;
  }
  if (a < 1 || b < 1 || a + b > MAX_CABLE_STITCHES) {
    problem = "a cable or twist of " + std::to_string(a) + " over " + std::to_string(b) +
              " stitches: expected 1 to " + std::to_string(MAX_CABLE_STITCHES) +
              " stitches in all, at least 1 in each group";
    return true;
  }
  sp.front = a;
  sp.back = b;
  sp.take = a + b;
  sp.back_face = twist ? Face::PURL : Face::KNIT;
  out = sp;
  return true;
}

// the symbol's spec; false when unknown
bool symbol_spec(const std::string& s, Spec& out, std::string& problem) {
  Spec sp;
  auto knit = [&](int take, Face face, std::initializer_list<int> order) {
    sp.op = Op::KNIT;
    sp.take = take;
    sp.face = face;
    sp.parents = 0;
    for (int k : order) sp.order[static_cast<std::size_t>(sp.parents++)] = k;
  };
  const Face K = Face::KNIT, P = Face::PURL;
  if (s == "k") {
    knit(1, K, {0});
  } else if (s == "p") {
    knit(1, P, {0});
  } else if (s == "ktbl") {
    knit(1, K, {0});
    sp.tbl = true;
  } else if (s == "ptbl") {
    knit(1, P, {0});
    sp.tbl = true;
  } else if (s == "k2tog") {
    knit(2, K, {1, 0});
  } else if (s == "p2tog") {
    knit(2, P, {1, 0});
  } else if (s == "ssk") {
    knit(2, K, {0, 1});
  } else if (s == "ssp") {
    knit(2, P, {0, 1});
  } else if (s == "k3tog") {
    knit(3, K, {2, 1, 0});
  } else if (s == "p3tog") {
    knit(3, P, {2, 1, 0});
  } else if (s == "sssk") {
    knit(3, K, {0, 1, 2});
  } else if (s == "sk2p" || s == "sl1k2togpsso") {
    knit(3, K, {1, 0, 2});
  } else if (s == "cdd" || s == "s2kp" || s == "s2kp2" || s == "sl2k1p2sso") {
    knit(3, K, {0, 2, 1});
  } else if (s == "yo") {
    sp.op = Op::NEW;
    sp.take = 0;
  } else if (s == "m1l" || s == "m1" || s == "m1r") {
    sp.op = Op::M1;
    sp.take = 0;
    sp.leans_left = s != "m1r";
  } else if (s == "sl" || s == "slwyib" || s == "slwyif") {
    sp.op = Op::SLIP;
    sp.wyif = s == "slwyif";
  } else if (s == "tuck") {
    sp.op = Op::TUCK;
  } else if (s == "bo") {
    sp.op = Op::BIND_OFF;
  } else if (s == "-") {
    sp.op = Op::UNWORKED;
  } else if (s == "w&t" || s == "wt") {
    sp.op = Op::WRAP;
  } else if (s == "ds") {
    sp.op = Op::DOUBLE;
  } else if (s == ".") {
    sp.op = Op::NONE;
    sp.take = 0;
  } else {
    return cable_spec(s, out, problem);
  }
  out = sp;
  return true;
}

const char* SYMBOL_LIST =
    "k, p, ktbl, ptbl, k2tog, p2tog, ssk, ssp, k3tog, p3tog, sssk, sk2p, cdd, yo, m1l, m1r, "
    "sl (slwyib), slwyif, tuck, bo, w&t, ds, '-' (unworked), '.' (no stitch), cables "
    "cNf/cNb/cX/Yf/cX/Yb, twists tNr/tNl/tX/Yr/tX/Yl, X/Ylc, X/Yrc, X/Ylpc, X/Yrpc";

class Builder {
 public:
  Builder(std::string_view text, std::string source) : m_text(text), m_source(std::move(source)) {}
  ChartResult run();

 private:
  [[noreturn]] void fail_line(int line, const std::string& what) const {
    throw std::invalid_argument(m_source + ":" + std::to_string(line) + ": " + what);
  }
  [[noreturn]] void fail_cell(int line, const Cell& c, const std::string& what) const {
    throw std::invalid_argument(m_source + ":" + std::to_string(line) + ":" +
                                std::to_string(c.text_col) + ": cell " + std::to_string(c.index) +
                                " '" + std::string(c.token) + "': " + what);
  }
  void parse();
  void header(int line, std::string_view key, std::string_view value);
  Row parse_row(int line, std::string_view body) const;
  std::uint32_t symbol_id(const std::string& symbol);
  void knit_row(int r, const Row& row);
  int yarn_of(std::string_view name, int row);
  LoopId make(int yarn, int row, int column, LoopKind kind, Face face, Direction d,
              std::span<const LoopId> parents, const std::string& symbol);

  std::string_view m_text;
  std::string m_source;
  ChartResult m_out;
  KnitGraph& g = m_out.graph;
  std::string m_default_yarn = "A";
  /// the row lines (line number, text without its comment), the top row first
  std::vector<std::pair<int, std::string_view>> m_rows;
  std::map<std::string, std::uint32_t, std::less<>> m_symbol_id;
  bool m_seen_row = false;
  std::map<std::string, int, std::less<>> m_yarn;  // name -> current piece (-1: cut)
  std::vector<std::vector<LoopId>> m_live;
  // short rows: unworked stitches at the end of the last row, and whether it wrapped
  int m_trailing = 0;
  bool m_wrapped = false;
};

void Builder::header(int line, std::string_view key, std::string_view value) {
  const std::string k = lower(trim(key));
  const std::string v = lower(trim(value));
  if (m_seen_row) fail_line(line, "header '" + k + ":' after the first row: headers come first");
  if (k == "knit") {
    if (v == "flat")
      m_out.in_the_round = false;
    else if (v == "round")
      m_out.in_the_round = true;
    else
      fail_line(line, "expected 'knit: flat' or 'knit: round', got '" + v + "'");
  } else if (k == "cells") {
    if (v == "rs")
      m_out.worked_cells = false;
    else if (v == "worked")
      m_out.worked_cells = true;
    else
      fail_line(line, "expected 'cells: rs' or 'cells: worked', got '" + v + "'");
  } else if (k == "yarn") {
    const std::string name(trim(value));
    if (!valid_yarn_name(name))
      fail_line(line,
                "expected 'yarn: NAME' (letters, digits, '_'; at most 32), got '" + name + "'");
    m_default_yarn = name;
  } else {
    fail_line(line, "unknown header '" + k + ":' (expected knit, cells or yarn)");
  }
}

Row Builder::parse_row(int line, std::string_view body) const {
  Row row;
  row.line = line;
  std::string_view row_yarn;
  std::size_t p = 0;
  const std::size_t base = static_cast<std::size_t>(body.data() - m_text.data());
  // text column of body[p]: from the line's start
  std::size_t line_start = base;
  while (line_start > 0 && m_text[line_start - 1] != '\n') --line_start;
  auto is_sep = [](char c) { return c == ' ' || c == '\t' || c == ',' || c == '\r'; };
  int index = 0, column = 1;
  while (p < body.size()) {
    while (p < body.size() && is_sep(body[p])) ++p;
    if (p >= body.size()) break;
    std::size_t q = p;
    while (q < body.size() && !is_sep(body[q])) ++q;
    const std::string_view tok = body.substr(p, q - p);
    const int text_col = static_cast<int>(base + p - line_start) + 1;
    p = q;
    ++index;
    Cell c;
    c.token = tok;
    c.text_col = text_col;
    c.index = index;
    // @YARN: the row's yarn (first token only)
    if (tok[0] == '@') {
      if (index != 1) fail_cell(line, c, "a row's yarn (@NAME) comes before its first cell");
      row_yarn = tok.substr(1);
      if (!valid_yarn_name(row_yarn))
        fail_cell(line, c, "expected @NAME, a yarn name (letters, digits, '_'; at most 32)");
      index = 0;
      continue;
    }
    std::string_view sym_text = tok;
    std::string_view yarn = row_yarn.empty() ? std::string_view(m_default_yarn) : row_yarn;
    const std::size_t at = tok.find('@');
    if (at != std::string_view::npos) {
      yarn = tok.substr(at + 1);
      sym_text = tok.substr(0, at);
      if (!valid_yarn_name(yarn))
        fail_cell(line, c, "expected SYMBOL@YARN, a yarn name (letters, digits, '_'; at most 32)");
    }
    std::string sym = lower(sym_text);
    if (sym.size() > 1)
      sym.erase(
          std::remove_if(sym.begin(), sym.end(), [](char ch) { return ch == '-' || ch == '_'; }),
          sym.end());
    if (sym.empty()) fail_cell(line, c, std::string("expected a stitch symbol: ") + SYMBOL_LIST);
    c.yarn = yarn;
    // a word of k and p letters: one cell each
    const bool kp_word = sym.size() > 1 && sym.find_first_not_of("kp") == std::string::npos;
    if (kp_word) {
      for (std::size_t i = 0; i < sym.size(); ++i) {
        Cell one = c;
        one.sym = std::string(1, sym[i]);
        one.index = index;
        std::string ignored;
        symbol_spec(one.sym, one.spec, ignored);
        one.column = column++;
        row.cells.push_back(one);
      }
      continue;
    }
    std::string problem;
    if (!symbol_spec(sym, c.spec, problem))
      fail_cell(line, c, "unknown stitch symbol: expected one of " + std::string(SYMBOL_LIST));
    if (!problem.empty()) fail_cell(line, c, problem);
    c.sym = sym;
    c.column = column;
    column += c.spec.width();
    row.cells.push_back(std::move(c));
  }
  if (row.cells.empty()) fail_line(line, "a row with a yarn and no cells: expected stitch cells");
  row.width = column - 1;
  return row;
}

std::uint32_t Builder::symbol_id(const std::string& symbol) {
  auto it = m_symbol_id.find(symbol);
  if (it != m_symbol_id.end()) return it->second;
  const auto id = static_cast<std::uint32_t>(m_out.symbols.size());
  m_out.symbols.push_back(symbol);
  m_symbol_id.emplace(symbol, id);
  return id;
}

void Builder::parse() {
  if (m_text.size() > MAX_CHART_TEXT_BYTES)
    throw std::invalid_argument(m_source + ": a chart of " + std::to_string(m_text.size()) +
                                " bytes: expected at most " + std::to_string(MAX_CHART_TEXT_BYTES));
  // a UTF-8 byte-order mark, as some editors write, is not a cell
  std::size_t p = m_text.substr(0, 3) == "\xEF\xBB\xBF" ? 3 : 0;
  int line = 0;
  while (p <= m_text.size()) {
    std::size_t e = m_text.find('\n', p);
    if (e == std::string_view::npos) e = m_text.size();
    ++line;
    std::string_view body = m_text.substr(p, e - p);
    const std::size_t hash = body.find('#');
    if (hash != std::string_view::npos) body = body.substr(0, hash);
    const std::string_view t = trim(body);
    if (!t.empty()) {
      const std::size_t colon = t.find(':');
      if (colon != std::string_view::npos && std::isalpha(static_cast<unsigned char>(t[0])))
        header(line, t.substr(0, colon), t.substr(colon + 1));
      else {
        if (m_rows.size() >= 1u << 20) fail_line(line, "more than 1048576 rows");
        m_seen_row = true;
        m_rows.emplace_back(line, body);
      }
    }
    if (e == m_text.size()) break;
    p = e + 1;
  }
  if (m_rows.empty())
    throw std::invalid_argument(m_source + ": no chart rows: expected at least one");
}

int Builder::yarn_of(std::string_view name, int row) {
  auto it = m_yarn.find(name);
  if (it == m_yarn.end() && m_yarn.size() >= MAX_CHART_YARNS)
    fail_line(m_out.row_line[static_cast<std::size_t>(row)],
              "yarn '" + std::string(name) + "' is the chart's " +
                  std::to_string(MAX_CHART_YARNS + 1) + "th yarn name: expected at most " +
                  std::to_string(MAX_CHART_YARNS));
  if (it == m_yarn.end() || it->second < 0) {
    const int y = g.add_yarn(std::string(name), row, false);
    m_yarn.insert_or_assign(std::string(name), y);
    return y;
  }
  return it->second;
}

LoopId Builder::make(int yarn, int row, int column, LoopKind kind, Face face, Direction d,
                     std::span<const LoopId> parents, const std::string& symbol) {
  if (g.num_loops() >= MAX_CHART_LOOPS)
    fail_line(m_out.row_line[static_cast<std::size_t>(row)],
              "the chart makes more than " + std::to_string(MAX_CHART_LOOPS) + " loops");
  Loop l;
  l.yarn = yarn;
  l.bed = Bed::FRONT;
  l.needle = column;
  l.pass = row;
  l.course = row;
  l.kind = kind;
  l.tucked = kind == LoopKind::TUCK;
  l.face = face;
  l.direction = d;
  l.line = row;
  const LoopId id = g.add_loop(l, parents);
  for (LoopId p : parents) g.consume_loop(p, row);
  m_out.loop_symbol.push_back(symbol_id(symbol));
  return id;
}

void Builder::knit_row(int r, const Row& row) {
  const int line = row.line;
  if (row.width != m_out.columns)
    fail_line(line, "the row covers " + std::to_string(row.width) + " grid columns, expected " +
                        std::to_string(m_out.columns) + " like line " +
                        std::to_string(m_rows.front().first) +
                        " (fill with '.' no-stitch cells; a cable covers its stitches)");
  const bool rs = m_out.in_the_round || r % 2 == 1;
  const bool flip_ws = m_out.worked_cells && !rs;
  const Direction dir = rs ? Direction::MINUS : Direction::PLUS;
  // cells in working order
  std::vector<const Cell*> work;
  for (const Cell& c : row.cells) work.push_back(&c);
  if (rs) std::reverse(work.begin(), work.end());

  // specs as seen from the right side (cells: worked, on a wrong-side row: the opposite)
  std::vector<Spec> spec;
  for (const Cell* c : work) {
    Spec s = c->spec;
    if (flip_ws) {
      s.face = flip(s.face);
      s.wyif = !s.wyif;
      s.leans_left = !s.leans_left;
      if (s.op == Op::CABLE) {
        std::swap(s.front, s.back);
        const Face f = s.front_face;
        s.front_face = flip(s.back_face);
        s.back_face = flip(f);
      }
    }
    spec.push_back(s);
  }

  // stitch count and the shape of the row: [unworked] worked [w&t] [unworked]
  int taken = 0;
  const int live = static_cast<int>(m_live.size());
  for (std::size_t i = 0; i < spec.size(); ++i) {
    if (spec[i].op == Op::CABLE && taken + spec[i].take > live)
      fail_cell(line, *work[i],
                "a cable or twist of " + std::to_string(spec[i].take) + " stitches, but only " +
                    std::to_string(std::max(0, live - taken)) +
                    " are left on the needle there: expected a cable no wider than the "
                    "stitches left");
    taken += spec[i].take;
  }
  if (taken != live)
    fail_line(line, "row " + std::to_string(r) + " works " + std::to_string(taken) +
                        " stitches, but " + std::to_string(live) + " are live after " +
                        (r == 1 ? std::string("the cast-on (row 1 sets it)")
                                : "row " + std::to_string(r - 1) + " (line " +
                                      std::to_string(m_out.row_line[r - 1]) + ")") +
                        ": expected cells that take exactly the live stitches");
  const std::size_t n = work.size();
  std::size_t first = 0, last = n;  // the worked part: [first, last)
  auto inert = [&](std::size_t i) { return spec[i].op == Op::UNWORKED || spec[i].op == Op::NONE; };
  while (first < n && inert(first)) ++first;
  while (last > first && inert(last - 1)) --last;
  if (first == last) fail_line(line, "row " + std::to_string(r) + " works no stitch");
  int leading = 0, trailing = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool unworked = spec[i].op == Op::UNWORKED;
    if (unworked && m_out.in_the_round)
      fail_cell(line, *work[i],
                "an unworked '-' cell in a chart knit in the round: short rows "
                "are charted flat (knit: flat)");
    if (unworked && i > first && i < last)
      fail_cell(line, *work[i],
                "an unworked '-' cell between worked stitches: expected '-' only "
                "at the ends of a row (short rows); to pass a stitch within a "
                "row, slip it (sl)");
    if (unworked) (i < first ? leading : trailing) += 1;
    const Op op = spec[i].op;
    if ((op == Op::WRAP || op == Op::DOUBLE) && m_out.in_the_round)
      fail_cell(line, *work[i],
                "short-row turns in a chart knit in the round: short rows are "
                "charted flat (knit: flat)");
    if (op == Op::WRAP && i != last - 1)
      fail_cell(line, *work[i],
                "a wrap and turn must be the row's last worked stitch: expected "
                "only unworked '-' (or '.') cells after it");
    if (op == Op::DOUBLE && i != first)
      fail_cell(line, *work[i],
                "a double stitch (German short rows) must be the row's first "
                "worked stitch, just after the turn");
    if (op == Op::BIND_OFF && i + 1 < last) {
      std::size_t j = i + 1;
      while (j < last && spec[j].op == Op::NONE) ++j;
      const Op next = spec[j].op;
      if (next == Op::NEW || next == Op::M1 || next == Op::SLIP || next == Op::TUCK ||
          next == Op::WRAP || next == Op::DOUBLE)
        fail_cell(line, *work[j],
                  "a bound-off stitch is passed over the next stitch made in "
                  "the row: expected a stitch worked into a loop (k, p, a "
                  "decrease, a cable, bo) after 'bo', or the end of the row");
    }
  }
  if (!m_out.in_the_round) {
    const int expected = m_trailing + (m_wrapped ? 1 : 0);
    if (leading != expected)
      fail_line(line, "row " + std::to_string(r) + " starts " + std::to_string(leading) +
                          " stitches in from its edge (leading unworked '-' cells, in working "
                          "order), but the yarn turned " +
                          std::to_string(expected) + " stitches in on the row below: expected " +
                          std::to_string(expected) + " leading '-' cells");
  }
  if (leading > 0 || trailing > 0 || spec[last - 1].op == Op::WRAP) m_out.short_rows.push_back(r);

  // the yarns: each used one's span of cells, for the floats of stranded colourwork
  std::map<int, std::pair<std::size_t, std::size_t>> span;  // yarn -> [first, last] cell
  std::vector<int> yarn(n, -1);
  for (std::size_t i = first; i < last; ++i) {
    if (spec[i].op == Op::NONE) continue;
    yarn[i] = yarn_of(work[i]->yarn, r);
    auto it = span.find(yarn[i]);
    if (it == span.end())
      span[yarn[i]] = {i, i};
    else
      it->second.second = i;
  }

  // work the stitches
  std::vector<std::vector<LoopId>> out;  // new stitches in working order
  int pos = rs ? live - 1 : 0;           // the next live stitch (index in m_live)
  std::vector<LoopId> last_taken;        // the stitch taken last
  auto take = [&](int k) {
    std::vector<std::vector<LoopId>> s(static_cast<std::size_t>(k));
    for (int i = 0; i < k; ++i) {
      const int at = rs ? pos - i : pos + i;
      // left to right: on a right-side row the first taken is the rightmost
      s[static_cast<std::size_t>(rs ? k - 1 - i : i)] =
          std::move(m_live[static_cast<std::size_t>(at)]);
    }
    pos += rs ? -k : k;
    if (k > 0) last_taken = rs ? s.front() : s.back();
    return s;
  };
  LoopId pending = NO_LOOP;  // the bound-off loop the next stitch passes through
  std::vector<LoopId> parents;
  for (std::size_t i = 0; i < n; ++i) {
    const Cell& c = *work[i];
    const Spec& s = spec[i];
    const int y = yarn[i];
    // the other yarns carried past this cell float behind it
    if (y >= 0)
      for (const auto& [other, sp] : span)
        if (other != y && sp.first < i && i < sp.second)
          for (int k = 0; k < s.width(); ++k) {
            if (m_out.floats.size() >= MAX_CHART_LOOPS)
              fail_line(line, "the chart's yarns float past more than " +
                                  std::to_string(MAX_CHART_LOOPS) + " stitches");
            g.add_miss(other, Bed::FRONT, c.column + k, dir, r);
            m_out.floats.push_back({other,
                                    g.yarns()[static_cast<std::size_t>(other)].steps.size() - 1,
                                    FloatSide::BACK});
          }
    switch (s.op) {
      case Op::NONE:
        break;
      case Op::UNWORKED: {
        auto st = take(1);
        out.push_back(std::move(st[0]));
        break;
      }
      case Op::KNIT:
      case Op::BIND_OFF: {
        auto st = take(s.take);
        parents.clear();
        if (s.op == Op::KNIT) {
          for (int j = 0; j < s.parents; ++j)
            for (LoopId l : st[static_cast<std::size_t>(s.order[static_cast<std::size_t>(j)])])
              parents.push_back(l);
        } else {
          for (LoopId l : st[0]) parents.push_back(l);
        }
        if (pending != NO_LOOP) parents.push_back(pending);
        pending = NO_LOOP;
        const Face face = s.face;
        const LoopId id = make(y, r, c.column, LoopKind::KNIT, face, dir, parents, c.sym);
        if (s.tbl) m_out.twisted.push_back(id);
        if (s.op == Op::BIND_OFF)
          pending = id;
        else
          out.push_back({id});
        break;
      }
      case Op::NEW: {
        const Face face = s.face;
        out.push_back({make(y, r, c.column, LoopKind::NEW, face, dir, {}, c.sym)});
        break;
      }
      case Op::M1: {
        const bool has_next = rs ? pos >= 0 : pos < live;
        if (last_taken.empty() || !has_next)
          fail_cell(line, c,
                    "an increase from the bar needs a stitch on each side (the bar "
                    "is the yarn between them): expected a stitch worked before it "
                    "in the row and one left to work");
        const LoopId before = last_taken.back();
        const LoopId after = m_live[static_cast<std::size_t>(pos)].back();
        const Face face = s.face;
        const LoopId id = make(y, r, c.column, LoopKind::NEW, face, dir, {}, c.sym);
        m_out.increases.push_back({id, rs ? after : before, rs ? before : after, s.leans_left});
        out.push_back({id});
        break;
      }
      case Op::SLIP: {
        auto st = take(1);
        g.add_miss(y, Bed::FRONT, c.column, dir, r);
        m_out.floats.push_back({y, g.yarns()[static_cast<std::size_t>(y)].steps.size() - 1,
                                s.wyif ? FloatSide::FRONT : FloatSide::BACK});
        out.push_back(std::move(st[0]));
        break;
      }
      case Op::TUCK:
      case Op::WRAP:
      case Op::DOUBLE: {
        auto st = take(1);
        const Face face = s.face;
        st[0].push_back(make(y, r, c.column, LoopKind::TUCK, face, dir, {}, c.sym));
        out.push_back(std::move(st[0]));
        break;
      }
      case Op::CABLE: {
        const int w = s.front + s.back;
        auto st = take(w);
        // the source stitch (index in st) of each of the cable's columns, left to right,
        // and whether the loop made there is in the front group
        std::vector<int> src(static_cast<std::size_t>(w));
        std::vector<bool> in_front(static_cast<std::size_t>(w));
        for (int k = 0; k < w; ++k) {
          if (s.front_left) {
            // the right `front` stitches go to the left
            const bool f = k < s.front;
            src[k] = f ? w - s.front + k : k - s.front;
            in_front[k] = f;
          } else {
            // the left `front` stitches go to the right
            const bool f = k >= w - s.front;
            src[k] = f ? k - (w - s.front) : s.front + k;
            in_front[k] = f;
          }
        }
        std::vector<LoopId> made(static_cast<std::size_t>(w), NO_LOOP);
        // made in working order of the columns they go to
        for (int t = 0; t < w; ++t) {
          const int k = rs ? w - 1 - t : t;
          parents.assign(st[src[k]].begin(), st[src[k]].end());
          if (pending != NO_LOOP) parents.push_back(pending);
          pending = NO_LOOP;
          const Face face = in_front[k] ? s.front_face : s.back_face;
          made[k] = make(y, r, c.column + k, LoopKind::KNIT, face, dir, parents, c.sym);
          out.push_back({made[k]});
        }
        for (int a = 0; a < w; ++a)
          for (int b = 0; b < w; ++b)
            if (in_front[a] && !in_front[b]) g.add_crossing(made[a], made[b], r);
        break;
      }
    }
  }
  if (pending != NO_LOOP) {
    // the row ends in a bind-off: the yarn is cut and its tail pulled through the last loop
    m_out.fastened_off.push_back(pending);
    const int y = g.loop(pending).yarn;
    g.end_yarn(y, r);
    for (auto& [name, piece] : m_yarn)
      if (piece == y) piece = -1;
  }
  if (rs) std::reverse(out.begin(), out.end());
  m_live = std::move(out);
  m_trailing = trailing;
  m_wrapped = spec[last - 1].op == Op::WRAP;
}

ChartResult Builder::run() {
  parse();
  // the top row sets the grid's width
  m_out.columns = parse_row(m_rows.front().first, m_rows.front().second).width;
  const int rows = static_cast<int>(m_rows.size());
  m_out.rows = rows;
  m_out.row_line.assign(static_cast<std::size_t>(rows) + 1, 0);
  m_out.right_side.assign(static_cast<std::size_t>(rows) + 1, true);
  for (int r = 1; r <= rows; ++r) {
    m_out.row_line[r] = m_rows[m_rows.size() - static_cast<std::size_t>(r)].first;
    m_out.right_side[r] = m_out.in_the_round || r % 2 == 1;
  }
  // the cast-on: as many loops as row 1 takes, left to right, by the yarn of row 1's
  // first stitch (in working order), under the cells that take them
  const Row first = parse_row(m_rows.back().first, m_rows.back().second);
  {
    std::vector<const Cell*> work;
    for (const Cell& c : first.cells) work.push_back(&c);
    if (m_out.right_side[1]) std::reverse(work.begin(), work.end());
    std::string_view name = m_default_yarn;
    for (const Cell* c : work)
      if (c->spec.op != Op::NONE && c->spec.op != Op::UNWORKED) {
        name = c->yarn;
        break;
      }
    const int y = yarn_of(name, 0);
    for (const Cell& c : first.cells)
      for (int k = 0; k < c.spec.take; ++k) {
        const int column = c.column + (c.spec.take == c.spec.width() ? k : 0);
        if (g.num_loops() >= MAX_CHART_LOOPS)
          fail_line(first.line,
                    "the cast-on makes more than " + std::to_string(MAX_CHART_LOOPS) + " loops");
        Loop l;
        l.yarn = y;
        l.needle = column;
        l.kind = LoopKind::NEW;
        l.direction = Direction::PLUS;
        const LoopId id = g.add_loop(l, {});
        m_out.loop_symbol.push_back(symbol_id("cast-on"));
        m_out.cast_on.push_back(id);
        m_live.push_back({id});
      }
    if (m_live.empty()) fail_line(first.line, "row 1 works no stitch: nothing to cast on");
  }
  m_out.stitches.push_back(static_cast<int>(m_live.size()));
  // about a loop per two bytes of text ("k ")
  const std::size_t guess = std::min(m_live.size() + m_text.size() / 2, MAX_CHART_LOOPS);
  g.reserve(guess);
  m_out.loop_symbol.reserve(guess);
  for (int r = 1; r <= rows; ++r) {
    if (r == 1) {
      knit_row(1, first);
    } else {
      const auto& [line, body] = m_rows[m_rows.size() - static_cast<std::size_t>(r)];
      knit_row(r, parse_row(line, body));
    }
    m_out.stitches.push_back(static_cast<int>(m_live.size()));
  }
  // yarns still in go out after the last row
  for (const auto& [name, piece] : m_yarn)
    if (piece >= 0) g.end_yarn(piece, rows);
  m_out.live = std::move(m_live);
  g.finish();
  return std::move(m_out);
}

}  // namespace

ChartResult read_chart_graph(std::string_view text, const std::string& source_name) {
  Builder b(text, source_name);
  return b.run();
}

ChartResult kp_rows_graph(const std::vector<std::string>& rows, const std::string& source_name) {
  std::string text;
  for (auto it = rows.rbegin(); it != rows.rend(); ++it) {
    if (it->find_first_not_of("kpKP") != std::string::npos || it->empty())
      throw std::invalid_argument(source_name + ":" + std::to_string(it - rows.rbegin() + 1) +
                                  ": expected a row of 'k' and 'p'");
    text += *it;
    text += '\n';
  }
  return read_chart_graph(text, source_name);
}

ChartResult load_chart_graph(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const auto status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw std::invalid_argument(path + ": no chart file there");
  if (!fs::is_regular_file(status)) throw std::invalid_argument(path + ": not a regular file");
  const auto size = fs::file_size(path, ec);
  if (ec) throw std::invalid_argument(path + ": cannot read its size");
  if (size > MAX_CHART_TEXT_BYTES)
    throw std::invalid_argument(path + ": a chart of " + std::to_string(size) +
                                " bytes: expected at most " + std::to_string(MAX_CHART_TEXT_BYTES));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::invalid_argument(path + ": cannot be opened");
  std::ostringstream s;
  s << in.rdbuf();
  return read_chart_graph(s.str(), path);
}

}  // namespace knit::graph
