// A run stopped and resumed is one run (runner.hpp): interrupted (SIGINT, SIGTERM) or
// killed (SIGKILL, after a checkpoint or a frame), and resumed any number of times in its
// directory, it ends with the uninterrupted run's files: the same final state and frames
// byte for byte, the same log rows (the wall seconds per step aside), and the same
// summary but for its wall-clock figures, which add up the legs, and for how its last leg
// was started (its command line, the state it resumed from). Checked from outside: the
// built knitsim, run and signalled as a user would, and the files it leaves.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "knit/io/state_file.hpp"
#include "run_knitsim.hpp"

namespace {

namespace fs = std::filesystem;

using knit::cli_test::Result;
using knit::cli_test::run;

// null where the file is not there yet (a run's first summary comes after its first log rows)
nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() ? nlohmann::json() : j;
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

int count_lines(const std::string& path) {
  std::ifstream in(path);
  int n = 0;
  for (std::string l; std::getline(in, l);) ++n;
  return n;
}

// ---- processes ----------------------------------------------------------------------

pid_t start(const std::string& args) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + KNIT_APP + " " + args + " >/dev/null 2>&1";
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// the exit code, or 128 + the signal that ended it
int wait_exit(pid_t pid) {
  int status = 0;
  waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// waits until `path` has more than `lines` lines; false when the process ended first (its
// exit code in `code`)
bool wait_past(pid_t pid, const std::string& path, int lines, int& code) {
  for (int k = 0; k < 6000; ++k) {
    if (count_lines(path) > lines) return true;
    int status;
    if (waitpid(pid, &status, WNOHANG) == pid) {
      code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

// The command the summary of a stopped run gives, without its program name (the test
// runs the build's knitsim).
std::string resume_args(const nlohmann::json& summary) {
  const std::string cmd = summary.at("resume_command");
  EXPECT_EQ(cmd.rfind("knitsim ", 0), 0u) << cmd;
  return cmd.substr(8);
}

// Starts `args` and sends `sig` once its log has two rows more than `rows`; returns the
// summary it was interrupted with (status "interrupted"), or null when it ended first.
nlohmann::json interrupt(const std::string& args, const std::string& dir, int sig) {
  const int rows = count_lines(dir + "/log.csv");
  const pid_t pid = start(args);
  int code = -1;
  if (!wait_past(pid, dir + "/log.csv", rows + 2, code)) {
    EXPECT_EQ(code, 0) << args;
    return nullptr;
  }
  kill(pid, sig);
  const int exit_code = wait_exit(pid);
  nlohmann::json s = read_json(dir + "/summary.json");
  EXPECT_TRUE(s.is_object()) << dir << "/summary.json: missing or unreadable after the signal";
  if (!s.is_object() || s["status"] == "ok") return nullptr;  // (the signal came as it was ending)
  EXPECT_EQ(exit_code, 128 + sig) << args;
  EXPECT_EQ(s["status"], "interrupted") << s.dump(2);
  return s;
}

// Interrupts `cmd` (SIGINT, then SIGTERM on its resume) in `dir`, each time going on with
// the summary's command, which `cmd` becomes; returns how many interrupts came before the end
// (2 unless the run ended first), with the last interrupted summary's wall time in `wall`.
int interrupt_twice(std::string& cmd, const std::string& dir, double& wall) {
  int stops = 0;
  for (int sig : {SIGINT, SIGTERM}) {
    const nlohmann::json s = interrupt(cmd, dir, sig);
    if (s.is_null()) break;
    ++stops;
    wall = s["wall_time_s"];
    cmd = resume_args(s);
  }
  return stops;
}

// Starts `args` (a relaxation without frames writing a checkpoint at every output step)
// and kills it outright (SIGKILL) once its log has two rows more than now, where its
// checkpoint's two files agree; returns the checkpoint's summary (status "running").
nlohmann::json kill_after_checkpoint(const std::string& args, const std::string& dir) {
  const int rows = count_lines(dir + "/log.csv");
  const pid_t pid = start(args);
  int code = -1;
  if (!wait_past(pid, dir + "/log.csv", rows + 2, code)) {
    EXPECT_EQ(code, 0) << args;
    return nullptr;
  }
  nlohmann::json s;
  for (int tries = 0; tries < 1000; ++tries) {
    kill(pid, SIGSTOP);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    s = read_json(dir + "/summary.json");
    if (s.is_object() && s.value("status", "") == "running" && fs::exists(dir + "/final.kstate") &&
        knit::read_state_file(dir + "/final.kstate").state.time == s["sim_time_s"].get<double>())
      break;
    kill(pid, SIGCONT);
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
  kill(pid, SIGKILL);
  EXPECT_EQ(wait_exit(pid), 128 + SIGKILL);
  EXPECT_EQ(s["status"], "running") << s.dump(2);
  return s;
}

// ---- the same run -------------------------------------------------------------------

// what a resumed run's summary may give otherwise: its wall-clock figures (sums over the
// legs) and how its last leg was started
const std::set<std::string> WALL_CLOCK = {"wall_time_s", "wall_s_per_simulated_s",
                                          "us_per_segment_step", "stage_seconds",
                                          "checkpoints_written"};
const std::set<std::string> LEG = {"command_line", "resumed_from"};

void expect_same_summary(const nlohmann::json& whole, const nlohmann::json& resumed) {
  std::set<std::string> keys;
  for (const auto& [k, v] : whole.items()) keys.insert(k);
  for (const auto& [k, v] : resumed.items()) keys.insert(k);
  for (const std::string& k : keys) {
    if (WALL_CLOCK.count(k) || LEG.count(k)) continue;
    ASSERT_TRUE(whole.contains(k)) << "only the resumed run's summary has " << k;
    ASSERT_TRUE(resumed.contains(k)) << "the resumed run's summary lacks " << k;
    EXPECT_EQ(whole[k], resumed[k])
        << k << ": uninterrupted " << whole[k].dump() << ", resumed " << resumed[k].dump();
  }
  for (const char* k : {"wall_time_s", "stage_seconds"}) EXPECT_TRUE(resumed.contains(k)) << k;
}

std::vector<std::vector<std::string>> csv_rows(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

// the same rows, every column but the wall seconds per step
void expect_same_log(const std::string& whole, const std::string& resumed) {
  const auto a = csv_rows(whole), b = csv_rows(resumed);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size()) << "log rows: uninterrupted " << a.size() << ", resumed "
                                << b.size();
  ASSERT_EQ(a[0], b[0]) << "log headers differ";
  size_t wall = a[0].size();
  for (size_t c = 0; c < a[0].size(); ++c)
    if (a[0][c] == "wall_s_per_step") wall = c;
  ASSERT_LT(wall, a[0].size());
  for (size_t r = 1; r < a.size(); ++r) {
    ASSERT_EQ(a[r].size(), b[r].size()) << "row " << r;
    for (size_t c = 0; c < a[r].size(); ++c) {
      if (c == wall) continue;  // (wall-clock)
      EXPECT_EQ(a[r][c], b[r][c]) << "row " << r << " (t = " << a[r][0] << "), " << a[0][c];
    }
  }
}

// The runs in `whole` and `cut` are the same run: the same state files byte for byte
// (the totals they carry included), log rows and summary; `earlier_wall_s`: the wall
// seconds the stopped legs' summaries gave at their ends, which the whole wall time
// includes.
void expect_same_run(const std::string& whole, const std::string& cut,
                     const std::vector<std::string>& states, double earlier_wall_s) {
  for (const std::string& f : states)
    EXPECT_TRUE(read_bytes(whole + "/" + f) == read_bytes(cut + "/" + f)) << f << " differs";
  if (fs::exists(whole + "/frames")) {
    std::vector<std::string> a, b;
    for (const auto& e : fs::directory_iterator(whole + "/frames"))
      a.push_back(e.path().filename());
    for (const auto& e : fs::directory_iterator(cut + "/frames"))
      if (e.path().extension() == ".kstate") b.push_back(e.path().filename());
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    EXPECT_EQ(a, b) << "other frames";
    for (const std::string& f : a)
      EXPECT_TRUE(read_bytes(whole + "/frames/" + f) == read_bytes(cut + "/frames/" + f))
          << "frame " << f << " differs";
  }
  expect_same_log(whole + "/log.csv", cut + "/log.csv");
  const nlohmann::json a = read_json(whole + "/summary.json");
  const nlohmann::json b = read_json(cut + "/summary.json");
  EXPECT_EQ(b["status"], "ok") << b.dump(2);
  expect_same_summary(a, b);
  EXPECT_GT(b["wall_time_s"].get<double>(), earlier_wall_s) << "the legs' wall time, summed";
}

// the tiny scene the simulations run: a yarn dropped across a yarn pinned at its ends, a
// ball beneath them both (contact, an object, and a duration that is not a multiple of
// the step: its last steps are shortened)
std::string tiny_scene() {
  const std::string path = ::testing::TempDir() + "/resume_scene.json";
  std::ofstream(path) << R"({
  "params": {"contact_points": 6},
  "gravity": [0, 0, -981],
  "time_step": 0.0001,
  "duration": 0.06015,
  "output_every": 20,
  "yarns": [
    {"line": {"from": [-3, 0, 0], "to": [3, 0, 0], "segments": 16}},
    {"line": {"from": [0.3, -2, 0.3], "to": [0.3, 2, 0.3], "segments": 12}}
  ],
  "pins": [{"yarn": 0, "at": "start"}, {"yarn": 0, "at": "end"}],
  "objects": [{"name": "ball", "sphere": {"center": [0, 0, -1.5], "radius": 1.2}}]
})";
  return path;
}

// ---- simulate -----------------------------------------------------------------------

// Interrupted by SIGINT, resumed and interrupted again by SIGTERM, resumed and killed
// outright (SIGKILL), then resumed from its latest frame: the run ends as the one that
// ran straight through.
TEST(Resume, ASimulationStoppedThreeTimesEndsAsTheUninterruptedOne) {
  const std::string dir = knit::cli_test::temp_dir("resume_simulate");
  const std::string args =
      "simulate " + tiny_scene() + " --max-step-halvings 2 --quiet --threads 2 --out ";
  ASSERT_EQ(run(args + dir + "/whole").code, 0);
  const nlohmann::json whole = read_json(dir + "/whole/summary.json");
  ASSERT_TRUE(whole.contains("min_contact_distance")) << whole.dump(2);
  ASSERT_TRUE(whole.contains("shortened_steps_s")) << whole.dump(2);
  ASSERT_TRUE(whole.contains("objects")) << whole.dump(2);
  const std::string cut = dir + "/cut";
  int stops = 0;
  double wall = 0;
  std::string cmd = args + cut;
  for (int sig : {SIGINT, SIGTERM}) {
    const nlohmann::json s = interrupt(cmd, cut, sig);
    if (s.is_null()) break;
    ++stops;
    EXPECT_LT(s["steps"].get<long long>(), whole["steps"].get<long long>());
    wall = s["wall_time_s"];
    cmd = resume_args(s);
  }
  ASSERT_EQ(stops, 2) << "the run ended before it was interrupted twice";
  // killed outright: its latest frame goes on
  {
    const int rows = count_lines(cut + "/log.csv");
    const pid_t pid = start(cmd);
    int code = -1;
    if (wait_past(pid, cut + "/log.csv", rows + 2, code)) {
      kill(pid, SIGKILL);
      EXPECT_EQ(wait_exit(pid), 128 + SIGKILL);
      std::vector<std::string> frames;  // (a frame being written when killed is a .tmp)
      for (const auto& e : fs::directory_iterator(cut + "/frames"))
        if (e.path().extension() == ".kstate") frames.push_back(e.path());
      std::sort(frames.begin(), frames.end());
      cmd = args + cut + " --resume " + frames.back();
      ++stops;
    }
  }
  const Result r = run(cmd);
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.output;
  expect_same_run(dir + "/whole", cut, {"final.kstate"}, wall);
}

// ---- relax --------------------------------------------------------------------------

const std::string RELAX =
    "relax garter --rows 4 --cols 4 --max-time 0.05 --check-every 20 --ke-threshold 1e-12 "
    "--quiet --threads 2";

// Interrupted twice (SIGINT, then SIGTERM) and resumed each time with its summary's
// command.
TEST(Resume, ARelaxationInterruptedTwiceEndsAsTheUninterruptedOne) {
  const std::string dir = knit::cli_test::temp_dir("resume_relax");
  ASSERT_EQ(run(RELAX + " --out " + dir + "/whole").code, 0);
  const std::string cut = dir + "/cut";
  std::string cmd = RELAX + " --out " + cut;
  double wall = 0;
  const int stops = interrupt_twice(cmd, cut, wall);
  ASSERT_EQ(stops, 2) << "the run ended before it was interrupted twice";
  const Result r = run(cmd);
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.output;
  expect_same_run(dir + "/whole", cut, {"initial.kstate", "final.kstate", "relaxed.kstate"}, wall);
}

// Without frames: killed outright after a checkpoint (the summary says "running"), resumed
// from it, interrupted (SIGINT), and resumed again.
TEST(Resume, ARelaxationKilledAfterACheckpointAndInterruptedEndsAsTheUninterruptedOne) {
  const std::string dir = knit::cli_test::temp_dir("resume_relax_ckpt");
  const std::string args = RELAX + " --no-frames --checkpoint-every 1e-9";
  ASSERT_EQ(run(args + " --out " + dir + "/whole").code, 0);
  const std::string cut = dir + "/cut";
  const nlohmann::json checkpoint = kill_after_checkpoint(args + " --out " + cut, cut);
  ASSERT_FALSE(checkpoint.is_null()) << "the run ended before it was killed";
  ASSERT_EQ(checkpoint["status"], "running");
  EXPECT_GT(checkpoint["checkpoints_written"].get<long long>(), 0);
  const nlohmann::json s = interrupt(resume_args(checkpoint), cut, SIGINT);
  ASSERT_FALSE(s.is_null()) << "the resumed run ended before it was interrupted";
  // the checkpoints of both legs
  EXPECT_GE(s["checkpoints_written"].get<long long>(),
            checkpoint["checkpoints_written"].get<long long>());
  const Result r = run(resume_args(s));
  ASSERT_EQ(r.code, 0) << r.output;
  expect_same_run(dir + "/whole", cut, {"initial.kstate", "final.kstate", "relaxed.kstate"},
                  s["wall_time_s"].get<double>());
}

// ---- stretch ------------------------------------------------------------------------

// A pull interrupted twice and resumed with its summary's command ends as the
// uninterrupted one, with the same curve.
TEST(Resume, APullInterruptedTwiceEndsAsTheUninterruptedOne) {
  const std::string dir = knit::cli_test::temp_dir("resume_stretch");
  const std::string args = "stretch --from " + std::string(KNIT_TEST_DATA) +
                           "/samples/stockinette_5x6.kstate --to 0.12 --no-render --quiet "
                           "--threads 2 --out ";
  ASSERT_EQ(run(args + dir + "/whole").code, 0);
  const std::string cut = dir + "/cut";
  std::string cmd = args + cut;
  double wall = 0;
  const int stops = interrupt_twice(cmd, cut, wall);
  ASSERT_EQ(stops, 2) << "the pull ended before it was interrupted twice";
  const Result r = run(cmd);
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.output;
  expect_same_run(dir + "/whole", cut, {"final.kstate"}, wall);
  EXPECT_EQ(read_bytes(dir + "/whole/stretch.csv"), read_bytes(cut + "/stretch.csv"));
}

// ---- state files --------------------------------------------------------------------

// A state a run wrote carries its totals; one resumed from a state without them (as
// earlier builds wrote) says that its summary covers the run from that state on.
TEST(Resume, AStateWithoutTotalsResumesWithASummarySayingSo) {
  const std::string dir = knit::cli_test::temp_dir("resume_no_totals");
  const std::string args = "simulate " + tiny_scene() + " --duration 0.004 --quiet --out " + dir;
  ASSERT_EQ(run(args).code, 0);
  knit::StateFile f = knit::read_state_file(dir + "/frames/state_000001.kstate");
  ASSERT_TRUE(f.run.has_value());
  EXPECT_EQ(f.run->steps, 20);
  EXPECT_EQ(f.run->frames_written, 2);  // the initial state's and this one
  f.run.reset();
  knit::write_state_file(dir + "/frames/state_000001.kstate", f);
  const Result r = run(args + " --resume " + dir + "/frames/state_000001.kstate");
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(dir + "/summary.json");
  EXPECT_EQ(s["totals_since_s"].get<double>(), f.state.time);
  EXPECT_EQ(s["steps"].get<long long>(), 20);  // of the 40, those after the state
  EXPECT_NE(s["totals_note"].get<std::string>().find("totals_since_s"), std::string::npos);
}

}  // namespace
