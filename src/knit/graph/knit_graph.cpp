#include "knit/graph/knit_graph.hpp"

#include <algorithm>
#include <cassert>
#include <stdexcept>

namespace knit::graph {

namespace {

std::uint64_t pair_key(LoopId a, LoopId b) {
  return (std::uint64_t{a} << 32) | b;
}

}  // namespace

const char* bed_name(Bed bed) {
  switch (bed) {
    case Bed::FRONT:
      return "f";
    case Bed::BACK:
      return "b";
    case Bed::FRONT_SLIDER:
      return "fs";
    case Bed::BACK_SLIDER:
      return "bs";
  }
  return "?";
}

const char* kind_name(LoopKind kind) {
  switch (kind) {
    case LoopKind::KNIT:
      return "knit";
    case LoopKind::TUCK:
      return "tuck";
    case LoopKind::SPLIT:
      return "split";
    case LoopKind::NEW:
      return "new";
  }
  return "?";
}

const char* face_name(Face face) {
  return face == Face::KNIT ? "knit" : "purl";
}

const char* end_name(LoopEnd end) {
  switch (end) {
    case LoopEnd::LIVE:
      return "live";
    case LoopEnd::DROPPED:
      return "dropped";
    case LoopEnd::CONSUMED:
      return "consumed";
  }
  return "?";
}

std::string needle_name(Bed bed, int needle) {
  return bed_name(bed) + std::to_string(needle);
}

void KnitGraph::reserve(std::size_t loops) {
  m_loops.reserve(loops);
  m_parents.reserve(loops);
  m_step_reserve = loops;
}

int KnitGraph::add_yarn(const std::string& carrier, int in_line, bool hook) {
  Yarn y;
  y.carrier = carrier;
  y.in_line = in_line;
  y.hook = hook;
  // the first yarn may well make every loop; later ones grow as they need
  if (m_yarns.empty()) y.steps.reserve(m_step_reserve);
  m_yarns.push_back(std::move(y));
  return static_cast<int>(m_yarns.size()) - 1;
}

void KnitGraph::end_yarn(int yarn, int out_line) {
  assert(yarn >= 0 && yarn < static_cast<int>(m_yarns.size()));
  m_yarns[static_cast<std::size_t>(yarn)].out_line = out_line;
}

LoopId KnitGraph::add_loop(Loop loop, std::span<const LoopId> parents) {
  assert(!m_finished);
  assert(loop.yarn >= 0 && loop.yarn < static_cast<int>(m_yarns.size()));
  if (m_loops.size() >= NO_LOOP - 1) throw std::length_error("knit graph: too many loops");
  loop.id = static_cast<LoopId>(m_loops.size());
  loop.parent_begin = static_cast<std::uint32_t>(m_parents.size());
  loop.parent_count = static_cast<std::uint32_t>(parents.size());
  loop.child_begin = loop.child_count = 0;
  loop.end = LoopEnd::LIVE;
  loop.end_line = 0;
  m_parents.insert(m_parents.end(), parents.begin(), parents.end());
  YarnStep step;
  step.kind = YarnStep::LOOP;
  step.loop = loop.id;
  step.bed = loop.bed;
  step.needle = loop.needle;
  step.direction = loop.direction;
  step.line = loop.line;
  m_yarns[static_cast<std::size_t>(loop.yarn)].steps.push_back(step);
  m_loops.push_back(loop);
  return loop.id;
}

void KnitGraph::add_miss(int yarn, Bed bed, int needle, Direction direction, int line) {
  assert(yarn >= 0 && yarn < static_cast<int>(m_yarns.size()));
  YarnStep step;
  step.kind = YarnStep::MISS;
  step.bed = bed;
  step.needle = needle;
  step.direction = direction;
  step.line = line;
  m_yarns[static_cast<std::size_t>(yarn)].steps.push_back(step);
}

void KnitGraph::consume_loop(LoopId loop, int line) {
  m_loops[loop].end = LoopEnd::CONSUMED;
  m_loops[loop].end_line = line;
}

void KnitGraph::drop_loop(LoopId loop, int line) {
  m_loops[loop].end = LoopEnd::DROPPED;
  m_loops[loop].end_line = line;
}

void KnitGraph::add_crossing(LoopId front, LoopId back, int line) {
  const auto key = pair_key(std::min(front, back), std::max(front, back));
  m_crossing_of[key] = {m_crossings_made++, Crossing{front, back, line}};
}

void KnitGraph::remove_crossing(LoopId a, LoopId b) {
  m_crossing_of.erase(pair_key(std::min(a, b), std::max(a, b)));
}

int KnitGraph::add_stitch_setting(StitchSetting setting) {
  m_settings.push_back(std::move(setting));
  return static_cast<int>(m_settings.size()) - 1;
}

void KnitGraph::finish() {
  // children: counting sort of the parent lists by parent
  for (Loop& l : m_loops) l.child_count = 0;
  for (LoopId p : m_parents) ++m_loops[p].child_count;
  std::uint32_t offset = 0;
  for (Loop& l : m_loops) {
    l.child_begin = offset;
    offset += l.child_count;
    l.child_count = 0;
  }
  m_children.assign(m_parents.size(), NO_LOOP);
  for (const Loop& l : m_loops)
    for (LoopId p : parents(l.id)) {
      Loop& parent = m_loops[p];
      m_children[parent.child_begin + parent.child_count++] = l.id;
    }
  m_finished = true;
}

std::span<const LoopId> KnitGraph::parents(LoopId id) const {
  const Loop& l = m_loops[id];
  return {m_parents.data() + l.parent_begin, l.parent_count};
}

std::span<const LoopId> KnitGraph::children(LoopId id) const {
  if (!m_finished) return {};
  const Loop& l = m_loops[id];
  return {m_children.data() + l.child_begin, l.child_count};
}

std::vector<Crossing> KnitGraph::crossings() const {
  std::vector<std::pair<std::uint64_t, Crossing>> made(m_crossing_of.size());
  std::size_t k = 0;
  for (const auto& [key, c] : m_crossing_of) made[k++] = c;
  std::sort(made.begin(), made.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Crossing> out;
  out.reserve(made.size());
  for (const auto& c : made) out.push_back(c.second);
  return out;
}

int KnitGraph::passes() const {
  return m_loops.empty() ? 0 : m_loops.back().pass + 1;
}

std::vector<std::size_t> KnitGraph::count_by_kind() const {
  std::vector<std::size_t> n(4, 0);
  for (const Loop& l : m_loops) ++n[static_cast<std::size_t>(l.kind)];
  return n;
}

GraphCheck KnitGraph::check() const {
  GraphCheck out;
  auto problem = [&](std::string text) {
    if (out.problems.size() < 20) out.problems.push_back(std::move(text));
  };
  // every yarn continuous: its loop steps are its own loops, in the order made, and every
  // loop is on exactly one yarn
  std::vector<int> seen(m_loops.size(), 0);
  for (std::size_t y = 0; y < m_yarns.size(); ++y) {
    const Yarn& yarn = m_yarns[y];
    LoopId last = NO_LOOP;
    int last_line = yarn.in_line;
    for (const YarnStep& s : yarn.steps) {
      if (s.line < last_line)
        problem("yarn " + std::to_string(y) + " (carrier " + yarn.carrier + "): a step at line " +
                std::to_string(s.line) + " follows one at line " + std::to_string(last_line));
      last_line = s.line;
      if (s.kind != YarnStep::LOOP) continue;
      if (s.loop >= m_loops.size()) {
        problem("yarn " + std::to_string(y) + " names loop " + std::to_string(s.loop) +
                ", which does not exist");
        continue;
      }
      if (m_loops[s.loop].yarn != static_cast<int>(y))
        problem("loop " + std::to_string(s.loop) + " is on yarn " + std::to_string(y) +
                " but was made by yarn " + std::to_string(m_loops[s.loop].yarn));
      if (last != NO_LOOP && s.loop <= last)
        problem("yarn " + std::to_string(y) + ": loop " + std::to_string(s.loop) +
                " follows loop " + std::to_string(last));
      last = s.loop;
      ++seen[s.loop];
    }
    if (yarn.out_line != 0 && yarn.out_line < last_line)
      problem("yarn " + std::to_string(y) + " goes out at line " + std::to_string(yarn.out_line) +
              " before its last step at line " + std::to_string(last_line));
  }
  for (const Loop& l : m_loops) {
    if (seen[l.id] != 1)
      problem("loop " + std::to_string(l.id) + " (line " + std::to_string(l.line) + ") is on " +
              std::to_string(seen[l.id]) + " yarn steps, not one");
    for (LoopId p : parents(l.id))
      if (p >= l.id)
        problem("loop " + std::to_string(l.id) + " (line " + std::to_string(l.line) +
                ") has parent " + std::to_string(p) + ", made after it");
    if ((l.kind == LoopKind::KNIT || l.kind == LoopKind::SPLIT) && l.parent_count == 0)
      problem("loop " + std::to_string(l.id) + " is a " + kind_name(l.kind) + " without parents");
    if ((l.kind == LoopKind::TUCK || l.kind == LoopKind::NEW) && l.parent_count != 0)
      problem("loop " + std::to_string(l.id) + " is a " + kind_name(l.kind) + " with parents");
    const bool held = m_finished ? l.child_count > 0 : false;
    if (l.end == LoopEnd::CONSUMED && !held)
      problem("loop " + std::to_string(l.id) + " was consumed at line " +
              std::to_string(l.end_line) + " but no loop is pulled through it");
    if (held) continue;
    if (l.end == LoopEnd::DROPPED)
      out.ladders.push_back(l.id);
    else if (l.end == LoopEnd::LIVE)
      out.free_live.push_back(l.id);
  }
  for (const Crossing& c : crossings())
    if (c.front >= m_loops.size() || c.back >= m_loops.size() || c.front == c.back)
      problem("a crossing at line " + std::to_string(c.line) + " names loops that do not exist");
  return out;
}

std::size_t KnitGraph::memory_bytes() const {
  std::size_t n = m_loops.capacity() * sizeof(Loop) +
                  (m_parents.capacity() + m_children.capacity()) * sizeof(LoopId) +
                  m_crossing_of.size() * (sizeof(Crossing) + 32);
  for (const Yarn& y : m_yarns) n += sizeof(Yarn) + y.steps.capacity() * sizeof(YarnStep);
  return n;
}

}  // namespace knit::graph
