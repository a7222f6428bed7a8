// What knitsim promises a user whatever they give it (docs/guarantees.md): bad input is
// refused before anything is written, with a message naming what is wrong; no run says
// "ok" for something it did not do; a signal ends a run with its state and a summary it
// can be resumed from, bit for bit; runs never mix in one directory.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "knit/io/state_file.hpp"
#include "knit/pattern/pattern.hpp"
#include "knit/scene/scene.hpp"
#include "run_knitsim.hpp"

namespace {

namespace fs = std::filesystem;

using knit::cli_test::Result;
using knit::cli_test::run;

std::string temp_dir(const std::string& name) {
  return knit::cli_test::temp_dir("rel_" + name);
}

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/rel_" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

nlohmann::json read_json(const std::string& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

const std::string PENDULUM = std::string(KNIT_EXAMPLES) + "/pendulum.json";

// the message names what is wrong, the run exits with 1, and nothing was written
void expect_refused(const std::string& args, const std::string& out, const std::string& names) {
  const Result r = run(args + " --out " + out);
  EXPECT_NE(r.code, 0) << args << "\n" << r.output;
  EXPECT_NE(r.output.find(names), std::string::npos) << args << "\n" << r.output;
  EXPECT_LT(r.output.size(), 2000u) << "a message should be short: " << r.output.substr(0, 300);
  EXPECT_FALSE(fs::exists(out)) << args << ": wrote " << out << " for refused input";
}

TEST(Reliability, DeeplyNestedSceneIsRefusedWithoutCrashing) {
  // a wrongly typed value nested 50,000 deep used to be dumped recursively in the message
  std::string deep = R"({"description": )" + std::string(50000, '[') + std::string(50000, ']') +
                     R"(, "yarns": []})";
  const std::string scene = write_file("deep.json", deep);
  const std::string out = temp_dir("deep_out");
  const Result r = run("simulate " + scene + " --out " + out);
  EXPECT_EQ(r.code, 1) << r.output.substr(0, 500);
  EXPECT_NE(r.output.find("nested more than"), std::string::npos) << r.output.substr(0, 500);
  EXPECT_FALSE(fs::exists(out));
  // a long wrongly typed value is described by its type and size, not printed
  const std::string wide =
      write_file("wide.json", R"({"description": [")" + std::string(100000, 'x') + R"(", 1]})");
  const Result w = run("simulate " + wide + " --out " + out);
  EXPECT_EQ(w.code, 1);
  EXPECT_NE(w.output.find("an array of 2 elements"), std::string::npos) << w.output;
  EXPECT_LT(w.output.size(), 400u);
  // and the parser's own messages are cut short too (a 100,000-digit number)
  const std::string number =
      write_file("number.json", R"({"duration": )" + std::string(100000, '1') + "}");
  const Result n = run("simulate " + number + " --out " + out);
  EXPECT_EQ(n.code, 1);
  EXPECT_NE(n.output.find("malformed JSON"), std::string::npos) << n.output.substr(0, 400);
  EXPECT_LT(n.output.size(), 500u);
}

TEST(Reliability, NumbersOutsideTheirRangeAreRefusedBeforeAnythingIsWritten) {
  const std::string out = temp_dir("numbers");
  for (const char* d : {"inf", "1e308", "1e-12", "-1", "nan", "0"})
    expect_refused("simulate " + PENDULUM + " --duration " + std::string(d), out, "duration");
  const std::string relax = "relax stockinette --rows 3 --cols 3 --quiet";
  for (const char* t : {"nan", "1e308", "1e-300"})
    expect_refused(relax + " --max-time " + t, out, "max-time");
  expect_refused(relax + " --time-step nan", out, "time-step");
  expect_refused(relax + " --k-global nan", out, "k-global");
  expect_refused(relax + " --shrink nan", out, "shrink");
  expect_refused(relax + " --shrink 0.5", out, "shrink");
  expect_refused(relax + " --alpha-small nan", out, "alpha-small");
  expect_refused(relax + " --ke-threshold 0", out, "ke-threshold");
  // range messages state the number shortly, not in 309 digits
  const Result big = run(relax + " --k-global 1e308 --out " + out);
  EXPECT_NE(big.output.find("1e+308"), std::string::npos) << big.output;
  EXPECT_LT(big.output.size(), 400u) << big.output;

  // scene fields
  auto scene = [](const std::string& fields) {
    return R"({"yarns": [{"line": {"from": [0,0,0], "to": [1,0,0], "segments": 4}}], )" + fields +
           "}";
  };
  const std::vector<std::pair<std::string, std::string>> bad_scenes = {
      {R"("time_step": 1e-300, "duration": 1)", "time_step"},
      {R"("time_step": 0.001, "duration": 1e308)", "duration"},
      {R"("time_step": 0.001, "duration": 0.0001)", "shorter than one time step"},
      {R"("params": {"k_contact": 1e300})", "params.k_contact"},
      {R"("params": {"contact_points": 1000000})", "params.contact_points"},
      {R"("gravity": [0, 0, 1e300])", "gravity"},
  };
  for (size_t k = 0; k < bad_scenes.size(); ++k) {
    const std::string path =
        write_file("scene" + std::to_string(k) + ".json", scene(bad_scenes[k].first));
    expect_refused("simulate " + path, out, bad_scenes[k].second);
  }
}

TEST(Reliability, ADurationThatIsNotAMultipleOfTheStepEndsAtTheTimeAsked) {
  const std::string out = temp_dir("odd_duration");
  // h = 1e-4: 2.5 steps, and 3.3 steps
  for (const char* d : {"0.00025", "0.00033"}) {
    fs::remove_all(out);
    const Result r = run("simulate " + PENDULUM + " --duration " + d + " --quiet --out " + out);
    ASSERT_EQ(r.code, 0) << r.output;
    const auto s = read_json(out + "/summary.json");
    EXPECT_NEAR(s["sim_time_s"].get<double>(), std::stod(d), 1e-15);
    EXPECT_TRUE(s.contains("time_note"));
    for (double step : s["shortened_steps_s"]) {
      EXPECT_GE(step, 0.5e-4 * (1 - 1e-12));
      EXPECT_LE(step, 1e-4);
    }
  }
  // a multiple takes exactly h every step
  fs::remove_all(out);
  ASSERT_EQ(run("simulate " + PENDULUM + " --duration 0.0003 --quiet --out " + out).code, 0);
  const auto s = read_json(out + "/summary.json");
  EXPECT_EQ(s["steps"], 3);
  EXPECT_FALSE(s.contains("shortened_steps_s"));
}

TEST(Reliability, StateFilesWithBadNumbersOrBitFlipsAreRefused) {
  const std::string out = temp_dir("kstate");
  fs::create_directories(out);
  const std::string good = out + "/good.kstate";
  ASSERT_EQ(run("relax stockinette --rows 2 --cols 2 --max-time 0.001 --quiet --no-frames --out " +
                out + "/relax")
                .code,
            0);
  fs::copy_file(out + "/relax/relaxed.kstate", good);
  knit::StateFile f = knit::read_state_file(good);
  // non-finite or negative numbers are refused by name, even without a checksum to break
  auto refused = [&](knit::StateFile bad, const std::string& what) {
    knit::write_state_file(out + "/bad.kstate", bad);
    try {
      knit::read_state_file(out + "/bad.kstate");
      ADD_FAILURE() << what << " was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  knit::StateFile nan_q = f;
  nan_q.state.q[7] = std::nan("");
  refused(nan_q, "position that is not finite");
  knit::StateFile nan_t = f;
  nan_t.state.time = std::nan("");
  refused(nan_t, "expected a finite time");
  knit::StateFile neg_t = f;
  neg_t.state.time = -1;
  refused(neg_t, "expected a finite time");
  // an export of such a file is refused too, instead of writing "nan" text
  const Result exp = run("export " + out + "/bad.kstate --format obj --out " + out + "/bad.obj");
  EXPECT_EQ(exp.code, 1);
  EXPECT_FALSE(fs::exists(out + "/bad.obj"));

  // every single-bit flip anywhere in the file is refused (the checksum covers all of it)
  std::ifstream in(good, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::mt19937 rng(7);
  int accepted = 0;
  for (int k = 0; k < 400; ++k) {
    std::string flipped = bytes;
    const size_t at = std::uniform_int_distribution<size_t>(0, bytes.size() - 1)(rng);
    flipped[at] = static_cast<char>(flipped[at] ^ (1 << (k % 8)));
    std::ofstream(out + "/flip.kstate", std::ios::binary) << flipped;
    try {
      knit::read_state_file(out + "/flip.kstate");
      ++accepted;
    } catch (const std::runtime_error&) {
    }
  }
  EXPECT_EQ(accepted, 0);
}

TEST(Reliability, InputsThatAreNotFilesAreRefusedByName) {
  const std::string out = temp_dir("not_files");
  // a directory given as a scene or chart
  const Result dir = run("simulate " + std::string(KNIT_EXAMPLES) + " --out " + out);
  EXPECT_EQ(dir.code, 1);
  EXPECT_NE(dir.output.find("is a directory"), std::string::npos) << dir.output;
  // a device is not read (it used to be read up to 2 GB)
  const Result zero = run("relax --from /dev/zero --quiet --out " + out);
  EXPECT_EQ(zero.code, 1);
  EXPECT_NE(zero.output.find("not a regular file"), std::string::npos) << zero.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST(Reliability, ChartsAcceptAByteOrderMarkAndNameBadBytes) {
  const knit::Pattern p = knit::parse_chart("\xEF\xBB\xBFkp\npk\n", "bom.chart");
  EXPECT_EQ(p.num_rows(), 2);
  EXPECT_EQ(p.num_cols(), 2);
  try {
    knit::parse_chart("kp\nk\x01\n", "bad.chart");
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("bad.chart:2:2"), std::string::npos) << m;
    EXPECT_NE(m.find("byte 0x01"), std::string::npos) << m;
    EXPECT_EQ(m.find('\x01'), std::string::npos) << "raw byte in the message";
  }
}

TEST(Reliability, KnitsThatCannotWorkAreRefusedUpFront) {
  const std::string out = temp_dir("knit_options");
  const std::string base = "relax stockinette --quiet --max-time 0.001";
  expect_refused(base + " --rows 1 --cols 4", out, "rows");
  expect_refused(base + " --rows 4 --cols 1", out, "cols");
  expect_refused(base + " --rows 4 --cols 4 --segments-per-stitch 4", out, "segments-per-stitch");
  expect_refused(base + " --rows 4 --cols 4 --segments-per-stitch 9", out, "segments-per-stitch");
  expect_refused(base + " --rows 4 --cols 4 --stitch-size 3", out, "stitch-size");
  expect_refused(base + " --rows 4 --cols 4 --stitch-size 13", out, "stitch-size");
  expect_refused(base + " --rows 4 --cols 3 --round", out, "in the round");
  // a size beyond the machine is refused at once, before any memory is taken
  const auto t0 = std::chrono::steady_clock::now();
  expect_refused(base + " --rows 100000 --cols 100000", out, "100000");
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 60.0);
}

TEST(Reliability, YarnsThatStartInsideEachOtherAreNamed) {
  const std::string line = R"({"line": {"from": [0,0,0], "to": [4,0,0], "segments": 8}})";
  const std::string scene =
      write_file("twins.json", R"({"gravity": [0,0,0], "duration": 0.01, "yarns": [)" + line +
                                   ", " + line + "]}");
  const std::string out = temp_dir("twins");
  expect_refused("simulate " + scene, out, "start inside each other");
}

TEST(Reliability, FastRigidMotionIsNotCalledUnstable) {
  // a yarn in free fall at 100 g passes a yarn radius per step after 12.5 ms
  const std::string scene =
      write_file("fall.json", R"({"gravity": [0,0,-1e5], "time_step": 1e-4, "duration": 0.03,
                      "yarns": [{"line": {"from": [0,0,0], "to": [4,0,0], "segments": 8}}]})");
  const std::string out = temp_dir("fall");
  const Result r = run("simulate " + scene + " --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  const auto s = read_json(out + "/summary.json");
  EXPECT_EQ(s["status"], "ok");
  // and it fell as far as free fall says (explicit midpoint is exact for constant force)
  const knit::StateFile f = knit::read_state_file(out + "/final.kstate");
  EXPECT_NEAR(f.state.q[2], -0.5 * 1e5 * 0.03 * 0.03, 1e-6);
}

TEST(Reliability, EverySummaryRecordsItsProvenance) {
  const std::string out = temp_dir("provenance");
  const Result v = run("--version");
  EXPECT_EQ(v.code, 0);
  EXPECT_NE(v.output.find(KNIT_VERSION), std::string::npos) << v.output;
  EXPECT_EQ(run("version").code, 0);
  ASSERT_EQ(run("simulate " + PENDULUM + " --duration 0.001 --quiet --out " + out).code, 0);
  const auto s = read_json(out + "/summary.json");
  EXPECT_EQ(s["knitsim_version"], KNIT_VERSION);
  EXPECT_NE(s["command_line"].get<std::string>().find("--duration 0.001"), std::string::npos);
  EXPECT_EQ(s["params"]["solver"]["time_step"], 1e-4);
  EXPECT_EQ(s["params"]["material"]["k_bend"], 5);
}

TEST(Reliability, RunsNeverMixInOneDirectory) {
  const std::string out = temp_dir("mixed");
  ASSERT_EQ(run("simulate " + PENDULUM + " --duration 0.002 --quiet --out " + out).code, 0);
  const Result again = run("simulate " + PENDULUM + " --duration 0.001 --quiet --out " + out);
  EXPECT_EQ(again.code, 1);
  EXPECT_NE(again.output.find("--overwrite"), std::string::npos) << again.output;
  // a render of a sequence into a directory holding other files is refused the same way
  const Result render = run("render " + out + "/frames --size 32x24 --out " + out);
  EXPECT_EQ(render.code, 1);
  EXPECT_NE(render.output.find("--overwrite"), std::string::npos) << render.output;
  // and a failed render leaves nothing behind
  const std::string png_dir = temp_dir("render_fail");
  const Result bad = run("render " + out + "/final.kstate --size 0x0 --out " + png_dir + "/a.png");
  EXPECT_EQ(bad.code, 1);
  EXPECT_FALSE(fs::exists(png_dir + "/a.png"));
  const Result jpg = run("render " + out + "/final.kstate --out " + png_dir + ".jpg");
  EXPECT_EQ(jpg.code, 1);
  EXPECT_NE(jpg.output.find(".png"), std::string::npos) << jpg.output;
  EXPECT_FALSE(fs::exists(png_dir + ".jpg"));
  for (const char* bad_out : {"/", "~"}) {
    const Result r = run("simulate " + PENDULUM + " --duration 0.001 --quiet --overwrite --out " +
                         std::string(bad_out));
    EXPECT_EQ(r.code, 1) << bad_out;
    EXPECT_NE(r.output.find("refusing"), std::string::npos) << r.output;
  }
}

// ---- signals and resume -------------------------------------------------------------

struct Child {
  pid_t pid;
};

Child start(const std::string& args) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + KNIT_APP + " " + args + " >/dev/null 2>&1";
    execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return {pid};
}

// waits until `path` has at least `lines` lines (or the child ended)
bool wait_for_lines(const Child& c, const std::string& path, int lines) {
  for (int k = 0; k < 6000; ++k) {
    std::ifstream in(path);
    int n = 0;
    std::string l;
    while (std::getline(in, l)) ++n;
    if (n >= lines) return true;
    int status;
    if (waitpid(c.pid, &status, WNOHANG) == c.pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

int wait_exit(const Child& c) {
  int status = 0;
  waitpid(c.pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

// Runs `args` to completion into DIR/whole, and again into DIR/cut interrupted by `sig`
// after a few written rows, then resumed with the summary's command. The two final states
// must be identical, bit for bit.
void interrupt_and_resume(const std::string& name, const std::string& args, int sig,
                          const std::string& final_name) {
  const std::string dir = temp_dir(name);
  ASSERT_EQ(run(args + " --threads 2 --out " + dir + "/whole").code, 0);
  const std::string cut = dir + "/cut";
  const Child c = start(args + " --threads 2 --out " + cut);
  ASSERT_TRUE(wait_for_lines(c, cut + "/log.csv", 3)) << "the run ended before it was interrupted";
  kill(c.pid, sig);
  EXPECT_EQ(wait_exit(c), 128 + sig);
  const auto s = read_json(cut + "/summary.json");
  EXPECT_EQ(s["status"], "interrupted");
  ASSERT_TRUE(s.contains("resume_command"));
  EXPECT_TRUE(fs::exists(cut + "/final.kstate"));
  const double t_cut = s["sim_time_s"];
  EXPECT_GT(t_cut, 0);
  // the summary's command, as a user would paste it (knitsim from the build)
  std::string cmd = s["resume_command"];
  ASSERT_EQ(cmd.rfind("knitsim ", 0), 0u) << cmd;
  // nothing in it needs quotes (a number of time left least of all: issue 51)
  EXPECT_EQ(cmd.find('\''), std::string::npos) << cmd;
  const Result r = run(cmd.substr(8));
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.output;
  EXPECT_EQ(read_bytes(dir + "/whole/" + final_name).substr(0, 64),
            read_bytes(cut + "/" + final_name).substr(0, 64));
  const knit::StateFile a = knit::read_state_file(dir + "/whole/" + final_name);
  const knit::StateFile b = knit::read_state_file(cut + "/" + final_name);
  EXPECT_EQ(a.state.time, b.state.time);
  EXPECT_TRUE(a.state.q == b.state.q) << "positions differ after the resume";
  EXPECT_TRUE(a.state.v == b.state.v) << "velocities differ after the resume";
  // the log goes on in order, without the rows of the interrupted tail twice
  std::ifstream log(cut + "/log.csv");
  std::string line;
  std::getline(log, line);
  double last = -1;
  while (std::getline(log, line)) {
    const double t = std::stod(line);
    EXPECT_GT(t, last) << "log rows out of order at t = " << t;
    last = t;
  }
  // frame times increase with their names
  std::vector<std::string> frames;
  if (fs::exists(cut + "/frames"))
    for (const auto& e : fs::directory_iterator(cut + "/frames")) frames.push_back(e.path());
  std::sort(frames.begin(), frames.end());
  double prev = -1;
  for (const std::string& f : frames) {
    const double t = knit::read_state_file(f).state.time;
    EXPECT_GT(t, prev) << f;
    prev = t;
  }
}

TEST(Reliability, AnInterruptedSimulationResumesBitForBit) {
  interrupt_and_resume(
      "sig_simulate",
      "simulate " + std::string(KNIT_EXAMPLES) + "/overhand_knot.json --duration 0.05 --quiet",
      SIGINT, "final.kstate");
}

TEST(Reliability, AnInterruptedRelaxationResumesBitForBit) {
  interrupt_and_resume("sig_relax",
                       "relax garter --rows 4 --cols 4 --max-time 0.04 --check-every 20 "
                       "--ke-threshold 1e-12 --quiet",
                       SIGTERM, "relaxed.kstate");
}

// A relaxation without frames killed outright (SIGKILL: nothing of its own runs) still
// leaves its last checkpoint: DIR/final.kstate and a summary that says "running" with the
// command that goes on from it, which ends where the whole run ends, bit for bit.
TEST(Reliability, AKilledRelaxationGoesOnFromItsCheckpoint) {
  const std::string dir = temp_dir("sigkill_relax");
  const std::string args =
      "relax garter --rows 4 --cols 4 --max-time 0.04 --check-every 20 --ke-threshold 1e-12 "
      "--no-frames --quiet --threads 2";
  ASSERT_EQ(run(args + " --out " + dir + "/whole").code, 0);
  const auto whole = read_json(dir + "/whole/summary.json");
  EXPECT_EQ(whole["status"], "ok");
  EXPECT_FALSE(whole.contains("checkpoints_written"));  // 600 s apart by default
  const std::string cut = dir + "/cut";
  const Child c = start(args + " --checkpoint-every 1e-9 --out " + cut);
  ASSERT_TRUE(wait_for_lines(c, cut + "/log.csv", 4)) << "the run ended before it was killed";
  // stopped where the checkpoint's two files agree (not between its two writes), then killed
  nlohmann::json s;
  for (int tries = 0; tries < 1000; ++tries) {
    ASSERT_EQ(kill(c.pid, SIGSTOP), 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    s = read_json(cut + "/summary.json");
    if (s.value("status", "") == "running" && fs::exists(cut + "/final.kstate") &&
        knit::read_state_file(cut + "/final.kstate").state.time == s["sim_time_s"].get<double>())
      break;
    kill(c.pid, SIGCONT);
    std::this_thread::sleep_for(std::chrono::milliseconds(3));
  }
  kill(c.pid, SIGKILL);
  EXPECT_EQ(wait_exit(c), 128 + SIGKILL);
  ASSERT_EQ(s["status"], "running");
  EXPECT_GT(s["sim_time_s"].get<double>(), 0);
  EXPECT_LT(s["sim_time_s"].get<double>(), 0.04);
  EXPECT_NE(s["message"].get<std::string>().find("final.kstate"), std::string::npos);
  ASSERT_TRUE(s.contains("resume_command"));
  std::string cmd = s["resume_command"];
  ASSERT_EQ(cmd.rfind("knitsim ", 0), 0u) << cmd;
  const Result r = run(cmd.substr(8));
  ASSERT_EQ(r.code, 0) << cmd << "\n" << r.output;
  const auto done = read_json(cut + "/summary.json");
  EXPECT_EQ(done["status"], "ok");
  const knit::StateFile a = knit::read_state_file(dir + "/whole/relaxed.kstate");
  const knit::StateFile b = knit::read_state_file(cut + "/relaxed.kstate");
  EXPECT_EQ(a.state.time, b.state.time);
  EXPECT_TRUE(a.state.q == b.state.q) << "positions differ after the resume";
  EXPECT_TRUE(a.state.v == b.state.v) << "velocities differ after the resume";
  // a checkpoint interval that is not a duration is refused by name
  const Result bad = run(args + " --checkpoint-every -1 --out " + dir + "/bad");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.output.find("--checkpoint-every"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(dir + "/bad"));
}

}  // namespace
