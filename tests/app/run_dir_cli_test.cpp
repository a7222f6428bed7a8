// Run directories from the command line: what a user's --out can and cannot lose.
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <thread>

#include "app/run_knitsim.hpp"

namespace knit::cli_test {
namespace {

namespace fs = std::filesystem;

const std::string PENDULUM = std::string(KNIT_EXAMPLES) + "/pendulum.json";

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

bool locked(const fs::path& dir) {
  const int fd = ::open((dir / ".knitsim-run").c_str(), O_RDONLY);
  if (fd < 0) return false;
  const bool busy = ::flock(fd, LOCK_EX | LOCK_NB) != 0;
  ::close(fd);
  return busy;
}

TEST(RunDirCli, AnEmptyOutIsRefusedByEveryCommand) {
  for (const std::string args :
       {"simulate " + PENDULUM + " --duration 0.001", std::string("relax garter --rows 2 --cols 2"),
        std::string("stretch garter --rows 4 --cols 4"), "render " + PENDULUM})
    for (const char* out : {"--out ''", "-o ''", "--out="}) {
      const Result r = run(args + " --quiet " + out);
      EXPECT_NE(r.code, 0) << args << " " << out;
      EXPECT_NE(r.output.find("--out"), std::string::npos) << r.output;
      // CLI11 reads `--out=` as no value at all: "missing"
      EXPECT_TRUE(r.output.find("empty") != std::string::npos ||
                  r.output.find("missing") != std::string::npos)
          << r.output;
      EXPECT_EQ(r.output.find("outputs in"), std::string::npos) << r.output;
    }
}

TEST(RunDirCli, OverwriteNeverRemovesAUsersFiles) {
  const fs::path root = temp_dir("rundir_cli_docs");
  fs::create_directories(root / "mydocs" / "photos");
  std::ofstream(root / "mydocs" / "thesis.txt") << "three years";
  std::ofstream(root / "mydocs" / "photos" / "a.jpg") << "jpg";
  for (const fs::path out : {root / "mydocs", root / "mydocs" / "photos" / ".."}) {
    const Result r =
        run("simulate " + PENDULUM + " --duration 0.001 --quiet --overwrite --out " + out.string());
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("thesis.txt"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("status ok"), std::string::npos) << r.output;
  }
  const Result relax =
      run("relax garter --rows 2 --cols 2 --max-time 0.001 --quiet --overwrite "
          "--out " +
          (root / "mydocs").string());
  EXPECT_EQ(relax.code, 1) << relax.output;
  EXPECT_EQ(read_text(root / "mydocs" / "thesis.txt"), "three years");
  EXPECT_TRUE(fs::exists(root / "mydocs" / "photos" / "a.jpg"));
  // a run's directory with a user's file added: refused, nothing removed
  const std::string run_dir = (root / "run").string();
  ASSERT_EQ(run("simulate " + PENDULUM + " --duration 0.01 --quiet --out " + run_dir).code, 0);
  std::ofstream(root / "run" / "notes.txt") << "mine";
  const Result added =
      run("simulate " + PENDULUM + " --duration 0.01 --quiet --overwrite --out " + run_dir);
  EXPECT_EQ(added.code, 1);
  EXPECT_NE(added.output.find("notes.txt"), std::string::npos) << added.output;
  EXPECT_TRUE(fs::exists(root / "run" / "summary.json"));
  fs::remove(root / "run" / "notes.txt");
  // and without it the overwrite goes through, the rendered sequence of it too
  EXPECT_EQ(
      run("simulate " + PENDULUM + " --duration 0.01 --quiet --overwrite --out " + run_dir).code,
      0);
  const std::string movie = (root / "movie").string();
  for (int k = 0; k < 2; ++k)
    EXPECT_EQ(run("render " + run_dir + "/frames --size 32x24 --overwrite --out " + movie).code, 0);
}

TEST(RunDirCli, ASecondRunIntoABusyDirectoryIsRefused) {
  const fs::path dir = temp_dir("rundir_cli_busy");
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd = std::string("exec ") + KNIT_APP + " simulate " + PENDULUM +
                            " --duration 100 --quiet --threads 1 --out " + dir.string() +
                            " >/dev/null 2>&1";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  bool seen = false;
  for (int k = 0; k < 3000 && !(seen = locked(dir)); ++k)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_TRUE(seen) << "the first run never locked its directory";
  for (const char* flag : {"", " --overwrite"}) {
    const Result r =
        run("simulate " + PENDULUM + " --duration 0.001 --quiet --out " + dir.string() + flag);
    EXPECT_EQ(r.code, 1) << r.output;
    EXPECT_NE(r.output.find("is writing into it"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("process " + std::to_string(pid)), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("filesystem error"), std::string::npos) << r.output;
  }
  ::kill(pid, SIGINT);  // the first run ends cleanly, its directory whole and unlocked
  int status = 0;
  ::waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGINT) << status;
  EXPECT_FALSE(locked(dir));
  EXPECT_NE(read_text(dir / "summary.json").find("--duration 100"), std::string::npos);
}

}  // namespace
}  // namespace knit::cli_test
