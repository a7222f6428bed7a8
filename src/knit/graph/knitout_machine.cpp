#include "knit/graph/knitout_machine.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "knit/util/input_file.hpp"

namespace knit::graph {

namespace {

constexpr std::string_view MAGIC = ";!knitout-";

struct NeedleRef {
  Bed bed = Bed::FRONT;
  int index = 0;
};

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

int sign(double x) {
  return x > 0 ? 1 : (x < 0 ? -1 : 0);
}

struct Carrier {
  bool in = false;
  int yarn = -1;
  Direction last_direction = Direction::NONE;
  int course = 0;
};

class Machine {
 public:
  Machine(std::string_view text, const std::string& source) : m_text(text), m_source(source) {}

  KnitoutResult run();

 private:
  // ---- messages ----
  [[noreturn]] void fail(const std::string& why) const {
    std::ostringstream msg;
    msg << m_source << ":" << m_line_no << ": ";
    if (!m_instruction.empty()) msg << "'" << knit::printable(m_instruction, 80) << "': ";
    msg << why;
    throw std::invalid_argument(msg.str());
  }
  void note(const std::string& key, const std::string& text) {
    const auto it = m_note_of.find(key);
    if (it != m_note_of.end()) {
      ++m_result.notes[it->second].count;
      return;
    }
    m_note_of.emplace(key, m_result.notes.size());
    m_result.notes.push_back({m_line_no, 1, text});
  }

  // ---- parsing ----
  void header_line(std::string_view line);
  void instruction(std::string_view code);
  Direction direction(std::string_view t) const {
    if (t == "+") return Direction::PLUS;
    if (t == "-") return Direction::MINUS;
    fail("expected a direction, '+' or '-', got '" + knit::printable(t) + "'");
  }
  NeedleRef needle(std::string_view t);
  double number(std::string_view t, const char* what) const;
  void expect_tokens(std::size_t min, std::size_t max, const char* form) const {
    if (m_tokens.size() < min || m_tokens.size() > max)
      fail(std::string("expected '") + form + "'");
  }
  // the carriers named from token `first` on, each checked against the header; `must_be_in`:
  // each must be in
  void carriers_from(std::size_t first, bool must_be_in);

  // ---- machine ----
  std::vector<LoopId>& stack(NeedleRef n) { return m_beds[static_cast<int>(n.bed)][n.index]; }
  std::vector<LoopId>* find_stack(NeedleRef n) {
    auto& bed = m_beds[static_cast<int>(n.bed)];
    const auto it = bed.find(n.index);
    return it == bed.end() ? nullptr : &it->second;
  }
  void clear_stack(NeedleRef n) { m_beds[static_cast<int>(n.bed)].erase(n.index); }
  void check_stack(NeedleRef n, std::size_t size) const {
    if (size > MAX_LOOPS_PER_NEEDLE)
      fail("needle " + needle_name(n.bed, n.index) + " would hold " + std::to_string(size) +
           " loops; a needle holds at most " + std::to_string(MAX_LOOPS_PER_NEEDLE) +
           " (a knit pulls a new loop through them)");
  }
  void check_stitch_needle(NeedleRef n) const {
    if (n.bed == Bed::FRONT_SLIDER || n.bed == Bed::BACK_SLIDER)
      fail(
          "expected a needle of the front or back bed (f or b): sliders hold loops during "
          "transfers only, no loop is formed on them");
  }
  void check_aligned(NeedleRef from, NeedleRef to) const;
  void step_carriers(Direction d);
  int next_pass(Direction d);
  void make_loops(std::string_view op, Direction d, NeedleRef n, LoopKind kind, Face face,
                  std::span<const LoopId> parents, std::vector<LoopId>& made);
  void move_loops(NeedleRef from, NeedleRef to);
  void rack_to(double r);
  void finish();

  std::string_view m_text;
  std::string m_source;
  KnitoutResult m_result;
  KnitGraph& g = m_result.graph;

  int m_line_no = 0;
  std::string_view m_instruction;
  std::vector<std::string_view> m_tokens;
  std::vector<std::string_view> m_cs;  ///< the instruction's carriers
  std::unordered_map<std::string, std::size_t> m_note_of;

  bool m_in_header = true;
  std::set<std::string, std::less<>> m_allowed;  ///< ;;Carriers: (empty: any name)
  int m_width = 0;                               ///< ;;Width: (0: none)
  int m_min_needle = 0, m_max_needle = 0;
  bool m_any_needle = false;

  std::map<int, std::vector<LoopId>> m_beds[4];
  double m_rack = 0;
  std::size_t m_rack_pairs = 0;
  std::vector<double> m_home;  ///< per loop: x where it was made (front-needle numbers)
  std::map<std::string, Carrier, std::less<>> m_carriers;
  std::vector<std::string> m_hook;  ///< carriers the inserting hook holds
  int m_setting = -1;
  // passes: the last loop-making instruction's direction and carriers
  Direction m_pass_direction = Direction::NONE;
  std::string m_pass_carriers;
  bool m_pass_break = true;
  int m_pass = -1;
  std::vector<LoopId> m_scratch, m_made;
};

NeedleRef Machine::needle(std::string_view t) {
  NeedleRef n;
  std::size_t prefix = 0;
  if (t.size() >= 2 && t[1] == 's' && (t[0] == 'f' || t[0] == 'b')) {
    n.bed = t[0] == 'f' ? Bed::FRONT_SLIDER : Bed::BACK_SLIDER;
    prefix = 2;
  } else if (!t.empty() && (t[0] == 'f' || t[0] == 'b')) {
    n.bed = t[0] == 'f' ? Bed::FRONT : Bed::BACK;
    prefix = 1;
  } else {
    fail("expected a needle such as f12, b-3, fs4 or bs4, got '" + knit::printable(t) + "'");
  }
  const char* begin = t.data() + prefix;
  const char* end = t.data() + t.size();
  long long index = 0;
  const auto res = std::from_chars(begin, end, index);
  if (begin == end || res.ec == std::errc::invalid_argument || res.ptr != end)
    fail("expected a needle such as f12, b-3, fs4 or bs4, got '" + knit::printable(t) + "'");
  if (res.ec == std::errc::result_out_of_range || index < -MAX_NEEDLE || index > MAX_NEEDLE)
    fail("needle '" + knit::printable(t) + "' is beyond the needles this interpreter models (" +
         std::to_string(-MAX_NEEDLE) + " to " + std::to_string(MAX_NEEDLE) + ")");
  n.index = static_cast<int>(index);
  // the bed's width: the needles a program uses must fit on it
  const int lo = m_any_needle ? std::min(m_min_needle, n.index) : n.index;
  const int hi = m_any_needle ? std::max(m_max_needle, n.index) : n.index;
  if (m_width > 0 && hi - lo + 1 > m_width)
    fail("needle " + needle_name(n.bed, n.index) + " is off the bed: the program's needles " +
         "would span " + std::to_string(lo) + " to " + std::to_string(hi) + ", " +
         std::to_string(hi - lo + 1) + " needles, and the bed has " + std::to_string(m_width) +
         " (;;Width: " + std::to_string(m_width) + ")");
  m_min_needle = lo;
  m_max_needle = hi;
  m_any_needle = true;
  return n;
}

double Machine::number(std::string_view t, const char* what) const {
  std::string_view s = t;
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  double v = 0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || res.ec != std::errc() || res.ptr != s.data() + s.size() || !std::isfinite(v))
    fail(std::string("expected ") + what + ", got '" + knit::printable(t) + "'");
  return v;
}

void Machine::carriers_from(std::size_t first, bool must_be_in) {
  m_cs.assign(m_tokens.begin() + static_cast<std::ptrdiff_t>(first), m_tokens.end());
  if (m_cs.size() > MAX_LOOPS_PER_NEEDLE)
    fail("expected at most " + std::to_string(MAX_LOOPS_PER_NEEDLE) + " carriers, got " +
         std::to_string(m_cs.size()));
  for (std::size_t k = 0; k < m_cs.size(); ++k) {
    const std::string_view c = m_cs[k];
    for (std::size_t j = 0; j < k; ++j)
      if (m_cs[j] == c) fail("carrier " + knit::printable(c) + " is named twice");
    if (!m_allowed.empty() && !m_allowed.count(c))
      fail("carrier '" + knit::printable(c) +
           "' is not one of the machine's carriers (;;Carriers:" +
           [&] {
             std::string all;
             for (const auto& a : m_allowed) all += " " + a;
             return all;
           }() +
           ")");
    if (must_be_in) {
      const auto it = m_carriers.find(c);
      if (it == m_carriers.end() || !it->second.in)
        fail("carrier " + std::string(c) + " is not in: bring it in first with 'in " +
             std::string(c) + "' or 'inhook " + std::string(c) + "'");
    }
  }
}

void Machine::check_aligned(NeedleRef from, NeedleRef to) const {
  if (is_front_side(from.bed) == is_front_side(to.bed))
    fail(
        "expected needles on opposite beds (a loop moves from the front bed to the back or "
        "back), got " +
        needle_name(from.bed, from.index) + " and " + needle_name(to.bed, to.index));
  const int f = is_front_side(from.bed) ? from.index : to.index;
  const int b = is_front_side(from.bed) ? to.index : from.index;
  if (m_rack != std::floor(m_rack)) {
    std::ostringstream r;
    r << m_rack;
    fail("at racking " + r.str() +
         " no needles are aligned for a transfer (expected a whole "
         "racking, such as 'rack " +
         std::to_string(f - b) + "' for these needles)");
  }
  if (static_cast<double>(f - b) != m_rack) {
    std::ostringstream r;
    r << m_rack;
    const double across = f - m_rack;
    std::ostringstream a;
    a << across;
    fail("at racking " + r.str() + ", f" + std::to_string(f) + " faces b" + a.str() + ", not b" +
         std::to_string(b) + ": expected 'rack " + std::to_string(f - b) +
         "' before this transfer");
  }
}

// the carriers of m_cs move in direction d: their courses turn when it changes
void Machine::step_carriers(Direction d) {
  for (std::string_view c : m_cs) {
    Carrier& car = m_carriers.find(c)->second;
    if (car.last_direction != Direction::NONE && car.last_direction != d) ++car.course;
    car.last_direction = d;
  }
}

int Machine::next_pass(Direction d) {
  std::string cs;
  for (std::string_view c : m_cs) {
    cs += c;
    cs += ' ';
  }
  if (m_pass_break || d != m_pass_direction || cs != m_pass_carriers) {
    ++m_pass;
    m_pass_direction = d;
    m_pass_carriers = std::move(cs);
    m_pass_break = false;
  }
  return m_pass;
}

void Machine::make_loops(std::string_view op, Direction d, NeedleRef n, LoopKind kind, Face face,
                         std::span<const LoopId> parents, std::vector<LoopId>& made) {
  made.clear();
  const int pass = next_pass(d);
  for (std::string_view c : m_cs) {
    if (g.num_loops() >= MAX_LOOPS)
      fail("the program makes more than " + std::to_string(MAX_LOOPS) +
           " loops, the most this interpreter keeps in memory");
    Carrier& car = m_carriers.find(c)->second;
    Loop l;
    l.yarn = car.yarn;
    l.bed = n.bed;
    l.needle = n.index;
    l.pass = pass;
    l.course = car.course;
    l.kind = kind;
    l.tucked = op == "tuck";
    l.face = face;
    l.direction = d;
    l.line = m_line_no;
    l.stitch_setting = m_setting;
    made.push_back(g.add_loop(l, parents));
    m_home.push_back(is_front_side(n.bed) ? n.index : n.index + m_rack);
  }
}

void Machine::move_loops(NeedleRef from, NeedleRef to) {
  std::vector<LoopId>* src = find_stack(from);
  if (!src || src->empty()) return;
  // taken out first: `to`'s insertion may rehash nothing (a map), but keep it plain
  std::vector<LoopId> moving = std::move(*src);
  clear_stack(from);
  std::vector<LoopId>& dst = stack(to);
  check_stack(to, dst.size() + moving.size());
  dst.insert(dst.end(), moving.begin(), moving.end());
}

// the back bed moves from racking m_rack to r. Two loops, one on each side, cross while
// their order across the beds (x, in front-needle numbers: a back needle j is at j + R) is
// the reverse of the order of the places they were made (home); the one on the front side
// when they came to cross passes in front. Loops side by side (equal x, or made at one
// place) do not cross. Only the pairs the back loop's sweep reaches can change.
void Machine::rack_to(double r) {
  const double r0 = m_rack;
  m_rack = r;
  if (r == r0) return;
  auto inverted = [](double xb, double xf, double hb, double hf) {
    return sign(xb - xf) * sign(hb - hf) < 0;
  };
  for (Bed back_bed : {Bed::BACK, Bed::BACK_SLIDER})
    for (const auto& [j, back_loops] : m_beds[static_cast<int>(back_bed)]) {
      if (back_loops.empty()) continue;
      const double x0 = j + r0, x1 = j + r;
      const double lo = std::min(x0, x1), hi = std::max(x0, x1);
      for (Bed front_bed : {Bed::FRONT, Bed::FRONT_SLIDER}) {
        const auto& front = m_beds[static_cast<int>(front_bed)];
        for (auto it = front.lower_bound(static_cast<int>(std::ceil(lo)));
             it != front.end() && it->first <= hi; ++it) {
          const double xf = it->first;
          m_rack_pairs += back_loops.size() * it->second.size();
          if (m_rack_pairs > MAX_RACK_PAIRS)
            fail("the program's racking carries more than " + std::to_string(MAX_RACK_PAIRS) +
                 " loop pairs past each other, more than this interpreter follows");
          for (LoopId b : back_loops)
            for (LoopId f : it->second) {
              const bool before = inverted(x0, xf, m_home[b], m_home[f]);
              const bool after = inverted(x1, xf, m_home[b], m_home[f]);
              if (after && !before) g.add_crossing(f, b, m_line_no);
              if (before && !after) g.remove_crossing(f, b);
            }
        }
      }
    }
}

void Machine::header_line(std::string_view line) {
  // ";;Name: value"
  const std::string_view body = line.substr(2);
  const std::size_t colon = body.find(':');
  if (colon == std::string_view::npos) return;  // a comment that looks like a header
  const std::string name(trim(body.substr(0, colon)));
  const std::string_view value = trim(body.substr(colon + 1));
  if (name.empty()) return;
  m_result.headers[name] = std::string(value);
  if (name == "Carriers") {
    m_allowed.clear();
    std::size_t p = 0;
    while (p < value.size()) {
      while (p < value.size() && is_space(value[p])) ++p;
      std::size_t q = p;
      while (q < value.size() && !is_space(value[q])) ++q;
      if (q > p) m_allowed.emplace(value.substr(p, q - p));
      p = q;
    }
  } else if (name == "Width") {
    long long w = 0;
    const auto res = std::from_chars(value.data(), value.data() + value.size(), w);
    if (value.empty() || res.ec != std::errc() || res.ptr != value.data() + value.size() || w < 1 ||
        w > 2 * MAX_NEEDLE + 1) {
      m_instruction = line;
      fail("expected ';;Width: N', the bed's number of needles (1 to " +
           std::to_string(2 * MAX_NEEDLE + 1) + ")");
    }
    m_width = static_cast<int>(w);
  } else if (name == "Machine" || name == "Gauge" || name == "Position" ||
             name.rfind("Yarn-", 0) == 0 || name.rfind("X-", 0) == 0 || name == "Extensions") {
    // recorded: they do not change what is knitted
  } else {
    note("header " + name, "header ';;" + name + ":' is not a knitout-2 header: kept, not used");
  }
}

void Machine::instruction(std::string_view code) {
  // tokens
  m_tokens.clear();
  std::size_t p = 0;
  while (p < code.size()) {
    while (p < code.size() && is_space(code[p])) ++p;
    std::size_t q = p;
    while (q < code.size() && !is_space(code[q])) ++q;
    if (q > p) m_tokens.push_back(code.substr(p, q - p));
    p = q;
  }
  if (m_tokens.empty()) return;
  m_instruction = trim(code);
  ++m_result.instructions;
  m_in_header = false;
  const std::string_view op = m_tokens[0];

  if (op == "knit" || op == "purl" || op == "tuck") {
    if (m_tokens.size() < 3) fail("expected '" + std::string(op) + " D N CS' (D: + or -)");
    const Direction d = direction(m_tokens[1]);
    const NeedleRef n = needle(m_tokens[2]);
    check_stitch_needle(n);
    carriers_from(3, true);
    if (op == "purl")
      note("purl",
           "'purl' is not a knitout-2 opcode: read as a knit whose loop is pulled the "
           "other way (purl as seen from its bed)");
    std::vector<LoopId>* held = find_stack(n);
    if (m_cs.empty()) {
      // no yarn: a knit drops, a tuck is an a-miss
      if (op != "tuck" && held) {
        for (LoopId l : *held) g.drop_loop(l, m_line_no);
        clear_stack(n);
      }
      return;
    }
    step_carriers(d);
    const bool front = is_front_side(n.bed);
    const bool pulled_to_front = (op == "purl") ? !front : front;
    const Face face = pulled_to_front ? Face::KNIT : Face::PURL;
    const bool empty = !held || held->empty();
    if (op == "tuck") {
      check_stack(n, (held ? held->size() : 0) + m_cs.size());
      make_loops(op, d, n, empty ? LoopKind::NEW : LoopKind::TUCK, face, {}, m_made);
      std::vector<LoopId>& s = stack(n);
      s.insert(s.end(), m_made.begin(), m_made.end());
    } else {
      m_scratch.assign(held ? held->begin() : m_scratch.end(),
                       held ? held->end() : m_scratch.end());
      if (!held) m_scratch.clear();
      make_loops(op, d, n, empty ? LoopKind::NEW : LoopKind::KNIT, face, m_scratch, m_made);
      for (LoopId l : m_scratch) g.consume_loop(l, m_line_no);
      stack(n).assign(m_made.begin(), m_made.end());
    }
  } else if (op == "split") {
    if (m_tokens.size() < 4) fail("expected 'split D N N2 CS' (D: + or -)");
    const Direction d = direction(m_tokens[1]);
    const NeedleRef n = needle(m_tokens[2]);
    const NeedleRef n2 = needle(m_tokens[3]);
    carriers_from(4, true);
    check_aligned(n, n2);
    if (m_cs.empty()) {
      move_loops(n, n2);
      m_pass_break = true;
      return;
    }
    check_stitch_needle(n);
    step_carriers(d);
    std::vector<LoopId>* held = find_stack(n);
    m_scratch.clear();
    if (held) m_scratch.assign(held->begin(), held->end());
    const Face face = is_front_side(n.bed) ? Face::KNIT : Face::PURL;
    make_loops(op, d, n, m_scratch.empty() ? LoopKind::NEW : LoopKind::SPLIT, face, m_scratch,
               m_made);
    move_loops(n, n2);
    stack(n).assign(m_made.begin(), m_made.end());
  } else if (op == "miss") {
    if (m_tokens.size() < 4) fail("expected 'miss D N CS' (D: + or -, at least one carrier)");
    const Direction d = direction(m_tokens[1]);
    const NeedleRef n = needle(m_tokens[2]);
    carriers_from(3, true);
    step_carriers(d);
    for (std::string_view c : m_cs)
      g.add_miss(m_carriers.find(c)->second.yarn, n.bed, n.index, d, m_line_no);
  } else if (op == "xfer") {
    expect_tokens(3, 3, "xfer N N2");
    const NeedleRef n = needle(m_tokens[1]);
    const NeedleRef n2 = needle(m_tokens[2]);
    check_aligned(n, n2);
    move_loops(n, n2);
    m_pass_break = true;
  } else if (op == "drop") {
    expect_tokens(2, 2, "drop N");
    const NeedleRef n = needle(m_tokens[1]);
    if (std::vector<LoopId>* held = find_stack(n)) {
      for (LoopId l : *held) g.drop_loop(l, m_line_no);
      clear_stack(n);
    }
  } else if (op == "amiss") {
    expect_tokens(2, 2, "amiss N");
    check_stitch_needle(needle(m_tokens[1]));
  } else if (op == "rack") {
    expect_tokens(2, 2, "rack R");
    const double r = number(m_tokens[1], "a racking such as 1, -2 or 0.25");
    if (std::abs(r) > MAX_RACK)
      fail("racking " + std::string(m_tokens[1]) + " is beyond the " +
           std::to_string(static_cast<int>(MAX_RACK)) + " needles this interpreter models");
    rack_to(r);
    m_pass_break = true;
  } else if (op == "in" || op == "inhook") {
    if (m_tokens.size() < 2) fail("expected '" + std::string(op) + " CS', at least one carrier");
    carriers_from(1, false);
    for (std::string_view c : m_cs) {
      auto it = m_carriers.find(c);
      if (it != m_carriers.end() && it->second.in)
        fail("carrier " + std::string(c) + " is already in (expected 'out " + std::string(c) +
             "' or 'outhook " + std::string(c) + "' before bringing it in again)");
    }
    if (op == "inhook" && !m_hook.empty())
      fail("the inserting hook still holds carrier(s)" + [&] {
        std::string s;
        for (const auto& h : m_hook) s += " " + h;
        return s;
      }() + ": expected 'releasehook' before another inhook");
    for (std::string_view c : m_cs) {
      Carrier& car = m_carriers[std::string(c)];
      car = Carrier{};
      car.in = true;
      car.yarn = g.add_yarn(std::string(c), m_line_no, op == "inhook");
    }
    if (op == "inhook") m_hook.assign(m_cs.begin(), m_cs.end());
  } else if (op == "releasehook") {
    if (m_tokens.size() < 2) fail("expected 'releasehook CS', at least one carrier");
    carriers_from(1, false);
    std::vector<std::string> named(m_cs.begin(), m_cs.end());
    std::vector<std::string> held = m_hook;
    std::sort(named.begin(), named.end());
    std::sort(held.begin(), held.end());
    if (held.empty()) fail("the inserting hook holds no carrier (expected 'inhook' before it)");
    if (named != held)
      fail(
          "the inserting hook holds carrier(s)" +
          [&] {
            std::string s;
            for (const auto& h : m_hook) s += " " + h;
            return s;
          }() +
          ", not these: expected 'releasehook" +
          [&] {
            std::string s;
            for (const auto& h : m_hook) s += " " + h;
            return s;
          }() +
          "'");
    m_hook.clear();
  } else if (op == "out" || op == "outhook") {
    if (m_tokens.size() < 2) fail("expected '" + std::string(op) + " CS', at least one carrier");
    carriers_from(1, true);
    for (std::string_view c : m_cs) {
      Carrier& car = m_carriers.find(c)->second;
      g.end_yarn(car.yarn, m_line_no);
      car.in = false;
      const auto h = std::find(m_hook.begin(), m_hook.end(), c);
      if (h != m_hook.end()) {
        note("out on hook",
             "a carrier taken out while the inserting hook still held it: the "
             "hook is released with it");
        m_hook.erase(h);
      }
    }
  } else if (op == "stitch") {
    expect_tokens(3, 3, "stitch L T");
    StitchSetting s;
    s.op = "stitch";
    s.value = number(m_tokens[1], "a stitch value L");
    s.value2 = number(m_tokens[2], "a stitch value T");
    s.line = m_line_no;
    m_setting = g.add_stitch_setting(std::move(s));
  } else if (op == "x-stitch-number") {
    expect_tokens(2, 2, "x-stitch-number N");
    StitchSetting s;
    s.op = "x-stitch-number";
    s.value = number(m_tokens[1], "a stitch number");
    s.line = m_line_no;
    m_setting = g.add_stitch_setting(std::move(s));
  } else if (op == "pause") {
    // the operator's pause changes nothing knitted
  } else if (op.size() > 2 && op.substr(0, 2) == "x-") {
    note(std::string(op), "extension '" + knit::printable(op) + "' is not interpreted: ignored");
  } else {
    fail("unknown instruction '" + knit::printable(op) +
         "' (expected a knitout-2 opcode: in, inhook, releasehook, out, outhook, knit, tuck, "
         "split, drop, amiss, xfer, miss, rack, stitch, pause, or an x- extension)");
  }
}

KnitoutResult Machine::run() {
  // about one loop per line: room for them all at once (at most MAX_LOOPS)
  const auto newlines = static_cast<std::size_t>(std::count(m_text.begin(), m_text.end(), '\n'));
  g.reserve(std::min(newlines + 1, MAX_LOOPS));
  std::size_t pos = 0;
  if (m_text.substr(0, 3) == "\xEF\xBB\xBF") pos = 3;
  bool crlf = false;
  while (pos < m_text.size()) {
    std::size_t end = m_text.find('\n', pos);
    if (end == std::string_view::npos) end = m_text.size();
    std::string_view line = m_text.substr(pos, end - pos);
    pos = end + 1;
    ++m_line_no;
    m_instruction = {};
    if (!line.empty() && line.back() == '\r') {
      line.remove_suffix(1);
      crlf = true;
    }
    if (m_line_no == 1) {
      if (line.substr(0, MAGIC.size()) != MAGIC)
        fail("not a knitout program: expected the first line ';!knitout-N'");
      const std::string_view v = trim(line.substr(MAGIC.size()));
      int version = 0;
      const auto res = std::from_chars(v.data(), v.data() + v.size(), version);
      if (v.empty() || res.ec != std::errc() || res.ptr != v.data() + v.size() || version < 0)
        fail("expected ';!knitout-N' with N a version number, got '" + knit::printable(line) + "'");
      m_result.version = version;
      if (version > 2)
        note("version", "knitout-" + std::to_string(version) +
                            " is newer than knitout-2, which this interpreter reads");
      continue;
    }
    if (line.find('\0') != std::string_view::npos)
      fail("the line holds a NUL byte: a knitout program is text");
    const std::size_t semi = line.find(';');
    if (semi != std::string_view::npos) {
      if (m_in_header && semi == 0 && line.substr(0, 2) == ";;") header_line(line);
      line = line.substr(0, semi);
    }
    instruction(line);
  }
  if (m_line_no == 0) fail("not a knitout program: the file is empty");
  m_result.lines = m_line_no;
  m_instruction = {};
  if (crlf) note("crlf", "lines end in CR LF; knitout's line ending is LF");
  finish();
  return std::move(m_result);
}

void Machine::finish() {
  for (const auto& [name, car] : m_carriers)
    if (car.in)
      note("still in " + name,
           "carrier " + name + " is still in at the end: its yarn is cut there");
  if (!m_hook.empty()) note("hook held", "the inserting hook still holds a carrier at the end");
  m_result.final_racking = m_rack;
  g.finish();
}

}  // namespace

KnitoutResult run_knitout(std::string_view text, const std::string& source_name) {
  Machine machine(text, source_name);
  return machine.run();
}

std::string read_knitout_text(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec && size > MAX_KNITOUT_BYTES)
    throw std::invalid_argument(
        path + ": " + knit::format_bytes(static_cast<double>(size)) +
        ", more than the 64 MB a knitout program may be (the limit bounds the memory its knit "
        "graph takes, about 8 times the program's size)");
  try {
    return knit::read_input_file(path, MAX_KNITOUT_BYTES, "knitout program");
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(e.what());
  }
}

KnitoutResult load_knitout_graph(const std::string& path) {
  return run_knitout(read_knitout_text(path), path);
}

}  // namespace knit::graph
