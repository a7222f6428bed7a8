#include "knit/pattern/graph_summary.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "knit/graph/chart.hpp"
#include "knit/graph/knitout_machine.hpp"
#include "knit/pattern/knitout.hpp"

namespace knit {

namespace {

namespace kg = knit::graph;

nlohmann::ordered_json loop_json(const kg::KnitGraph& g, kg::LoopId id) {
  const kg::Loop& l = g.loop(id);
  nlohmann::ordered_json j = {{"id", l.id},
                              {"yarn", l.yarn},
                              {"needle", kg::needle_name(l.bed, l.needle)},
                              {"pass", l.pass},
                              {"course", l.course},
                              {"kind", kg::kind_name(l.kind)},
                              {"face", kg::face_name(l.face)},
                              {"direction", l.direction == kg::Direction::PLUS ? "+" : "-"},
                              {"line", l.line},
                              {"end", kg::end_name(l.end)}};
  if (l.end != kg::LoopEnd::LIVE) j["end_line"] = l.end_line;
  const auto p = g.parents(id);
  j["parents"] = std::vector<kg::LoopId>(p.begin(), p.end());
  if (l.stitch_setting >= 0) j["stitch_setting"] = l.stitch_setting;
  return j;
}

// what the graph holds, after `j`'s lines about where it came from
void add_graph_json(nlohmann::ordered_json& j, const kg::KnitGraph& g, bool loops) {
  const kg::GraphCheck check = g.check();
  const auto kinds = g.count_by_kind();
  std::size_t purl = 0, back = 0;
  for (const kg::Loop& l : g.loops()) {
    purl += l.face == kg::Face::PURL;
    back += !kg::is_front_side(l.bed);
  }
  j["loops"] = {{"total", g.num_loops()}, {"knit", kinds[0]},
                {"tuck", kinds[1]},       {"split", kinds[2]},
                {"new", kinds[3]},        {"knit_face", g.num_loops() - purl},
                {"purl_face", purl},      {"front_bed", g.num_loops() - back},
                {"back_bed", back}};
  j["passes"] = g.passes();
  nlohmann::ordered_json yarns = nlohmann::ordered_json::array();
  for (std::size_t y = 0; y < g.yarns().size(); ++y) {
    const kg::Yarn& yarn = g.yarns()[y];
    std::size_t made = 0, misses = 0;
    int courses = 0;
    for (const kg::YarnStep& s : yarn.steps) {
      if (s.kind == kg::YarnStep::LOOP) {
        ++made;
        courses = std::max(courses, g.loop(s.loop).course + 1);
      } else {
        ++misses;
      }
    }
    nlohmann::ordered_json yj = {
        {"index", y},    {"carrier", yarn.carrier}, {"in_line", yarn.in_line}, {"hook", yarn.hook},
        {"loops", made}, {"misses", misses},        {"courses", courses}};
    yj["out_line"] =
        yarn.out_line > 0 ? nlohmann::ordered_json(yarn.out_line) : nlohmann::ordered_json(nullptr);
    if (!yarn.steps.empty()) {
      yj["first_needle"] = kg::needle_name(yarn.steps.front().bed, yarn.steps.front().needle);
      yj["last_needle"] = kg::needle_name(yarn.steps.back().bed, yarn.steps.back().needle);
    }
    yarns.push_back(yj);
  }
  j["yarns"] = yarns;
  auto free_list = [&](const std::vector<kg::LoopId>& ids) {
    nlohmann::ordered_json a = nlohmann::ordered_json::array();
    for (kg::LoopId id : ids) {
      const kg::Loop& l = g.loop(id);
      nlohmann::ordered_json e = {{"loop", id},
                                  {"needle", kg::needle_name(l.bed, l.needle)},
                                  {"kind", kg::kind_name(l.kind)},
                                  {"line", l.line}};
      if (l.end == kg::LoopEnd::DROPPED) e["dropped_line"] = l.end_line;
      a.push_back(e);
    }
    return a;
  };
  j["free_loops"] = {{"live", free_list(check.free_live)}, {"dropped", free_list(check.ladders)}};
  nlohmann::ordered_json crossings = nlohmann::ordered_json::array();
  for (const kg::Crossing& c : g.crossings())
    crossings.push_back(
        {{"front", c.front},
         {"back", c.back},
         {"front_needle", kg::needle_name(g.loop(c.front).bed, g.loop(c.front).needle)},
         {"back_needle", kg::needle_name(g.loop(c.back).bed, g.loop(c.back).needle)},
         {"line", c.line}});
  j["crossings"] = crossings;
  nlohmann::ordered_json settings = nlohmann::ordered_json::array();
  for (const kg::StitchSetting& s : g.stitch_settings()) {
    nlohmann::ordered_json e = {{"op", s.op}, {"value", s.value}, {"line", s.line}};
    if (s.op == "stitch") e["value2"] = s.value2;
    settings.push_back(e);
  }
  j["stitch_settings"] = settings;
  j["problems"] = check.problems;
  if (loops) {
    nlohmann::ordered_json all = nlohmann::ordered_json::array();
    for (kg::LoopId id = 0; id < g.num_loops(); ++id) all.push_back(loop_json(g, id));
    j["loop_list"] = all;
  }
}

nlohmann::ordered_json knitout_json(const std::string& path, const kg::KnitoutResult& r,
                                    bool loops) {
  nlohmann::ordered_json j;
  j["program"] = path;
  j["knitout_version"] = r.version;
  j["lines"] = r.lines;
  j["instructions"] = r.instructions;
  j["headers"] = r.headers;
  add_graph_json(j, r.graph, loops);
  nlohmann::ordered_json notes = nlohmann::ordered_json::array();
  for (const kg::KnitoutNote& n : r.notes)
    notes.push_back({{"line", n.line}, {"count", n.count}, {"text", n.text}});
  j["notes"] = notes;
  return j;
}

// what `relax` lays of the program: the sheet the generator knits, or why not
nlohmann::ordered_json sheet_json(const std::string& path, const std::string& text,
                                  const kg::KnitoutResult& r) {
  try {
    const KnitoutPiece p = knitout_sheet(r, text, path);
    return {{"laid", true},
            {"rows", p.rows()},
            {"cols", p.cols()},
            {"in_the_round", p.in_the_round},
            {"first_row_leftward", p.pattern.first_row_leftward}};
  } catch (const std::invalid_argument& e) {
    return {{"laid", false}, {"why_not", e.what()}};
  }
}

nlohmann::ordered_json chart_json(const std::string& path, const kg::ChartResult& r, bool loops) {
  nlohmann::ordered_json j;
  j["chart"] = path;
  j["rows"] = r.rows;
  j["columns"] = r.columns;
  j["in_the_round"] = r.in_the_round;
  j["stitches_per_row"] = r.stitches;  // [0]: cast on
  j["symbols"] = r.symbols;
  j["twisted"] = r.twisted.size();
  j["short_rows"] = r.short_rows.size();
  add_graph_json(j, r.graph, loops);
  return j;
}

}  // namespace

bool is_chart_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".chart";
}

nlohmann::ordered_json knit_graph_json(const std::string& path, bool loops) {
  if (is_chart_path(path)) return chart_json(path, kg::load_chart_graph(path), loops);
  const std::string text = kg::read_knitout_text(path);
  const kg::KnitoutResult r = kg::run_knitout(text, path);
  nlohmann::ordered_json j = knitout_json(path, r, loops);
  j["sheet"] = sheet_json(path, text, r);
  return j;
}

}  // namespace knit
