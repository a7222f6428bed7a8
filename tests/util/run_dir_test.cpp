// Run directories: --overwrite removes exactly what knitsim runs wrote, never anything else,
// and a directory is locked while a run writes it.
#include "knit/util/run_dir.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>

#include "io/test_states.hpp"
#include "knit/io/state_file.hpp"
#include "knit/util/atomic_file.hpp"

namespace knit {
namespace {

namespace fs = std::filesystem;

void put(const fs::path& p, const std::string& text = "x") {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

std::string refusal(const std::string& dir, bool overwrite) {
  try {
    const RunDirectory d = prepare_run_directory(dir, overwrite);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

// a run: the directory prepared, two files and a folder written as runs write them
void fake_run(const fs::path& dir, bool overwrite) {
  const RunDirectory d = prepare_run_directory(dir.string(), overwrite);
  write_file_atomic((dir / "summary.json").string(), "{}\n");
  fs::create_directories(dir / "frames");
  claim_run_output((dir / "frames").string());
  write_file_atomic((dir / "frames" / "state_000001.kstate").string(), "state");
}

// flock on another open of the marker: what another process's run holds
int hold_elsewhere(const fs::path& dir) {
  const int fd = ::open((dir / RUN_MARKER).c_str(), O_RDONLY);
  EXPECT_GE(fd, 0);
  EXPECT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  return fd;
}

bool locked(const fs::path& dir) {
  const int fd = ::open((dir / RUN_MARKER).c_str(), O_RDONLY);
  if (fd < 0) return false;
  const bool busy = ::flock(fd, LOCK_EX | LOCK_NB) != 0;
  ::close(fd);
  return busy;
}

TEST(RunDirectory, OverwriteRemovesOnlyWhatRunsWrote) {
  const fs::path dir = test::temp_dir("rundir-own") / "run";
  fake_run(dir, false);
  EXPECT_TRUE(fs::exists(dir / RUN_MARKER));
  const std::string marker = read_text(dir / RUN_MARKER);
  EXPECT_NE(marker.find("\"summary.json\""), std::string::npos) << marker;
  EXPECT_NE(marker.find("\"frames/state_000001.kstate\""), std::string::npos) << marker;
  // without --overwrite the earlier run is left whole
  const std::string again = refusal(dir.string(), false);
  EXPECT_NE(again.find("already holds an earlier run's files"), std::string::npos) << again;
  EXPECT_NE(again.find("--overwrite"), std::string::npos) << again;
  EXPECT_TRUE(fs::exists(dir / "frames" / "state_000001.kstate"));
  // an atomic write cut short leaves NAME.tmp: the run's too
  put(dir / "frames" / "state_000001.kstate.tmp");
  {
    const RunDirectory d = prepare_run_directory(dir.string(), true);
    EXPECT_EQ(fs::path(d.path()), fs::canonical(dir));
  }
  EXPECT_TRUE(fs::exists(dir / RUN_MARKER));
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  EXPECT_FALSE(fs::exists(dir / "frames"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
  // the new run's marker names nothing of the old one's
  EXPECT_EQ(read_text(dir / RUN_MARKER).find("summary.json"), std::string::npos);
}

TEST(RunDirectory, SomeoneElsesFilesAreNeverRemoved) {
  const fs::path docs = test::temp_dir("rundir-docs");
  put(docs / "thesis.txt", "three years");
  put(docs / "photos" / "a.jpg");
  for (bool overwrite : {false, true}) {
    const std::string r = refusal(docs.string(), overwrite);
    EXPECT_NE(r.find("no knitsim run marker"), std::string::npos) << r;
    EXPECT_NE(r.find("thesis.txt"), std::string::npos) << r;
    EXPECT_NE(r.find("photos/"), std::string::npos) << r;
    EXPECT_THROW(check_run_directory(docs.string(), overwrite), std::invalid_argument);
  }
  EXPECT_EQ(read_text(docs / "thesis.txt"), "three years");
  EXPECT_TRUE(fs::exists(docs / "photos" / "a.jpg"));
  EXPECT_FALSE(fs::exists(docs / RUN_MARKER)) << "a refused directory was marked";
  // a source folder of a repository (no .git of its own) is someone else's the same way
  put(docs / "repo" / ".git" / "HEAD");
  put(docs / "repo" / "src" / "main.c", "int main;");
  EXPECT_NE(refusal((docs / "repo" / "src").string(), true).find("main.c"), std::string::npos);
  EXPECT_NE(refusal((docs / "repo").string(), true).find("refusing"), std::string::npos);
  EXPECT_TRUE(fs::exists(docs / "repo" / "src" / "main.c"));
  // DIR/sub/.. is DIR
  const std::string up = refusal((docs / "photos" / "..").string(), true);
  EXPECT_NE(up.find("thesis.txt"), std::string::npos) << up;
  EXPECT_TRUE(fs::exists(docs / "photos" / "a.jpg"));
}

TEST(RunDirectory, AFileAddedToARunDirectoryStopsTheOverwrite) {
  const fs::path dir = test::temp_dir("rundir-added") / "run";
  fake_run(dir, false);
  put(dir / "notes.txt", "mine");
  put(dir / "frames" / "sketch.png", "mine too");
  const std::string r = refusal(dir.string(), true);
  EXPECT_NE(r.find("no knitsim run wrote"), std::string::npos) << r;
  EXPECT_NE(r.find("notes.txt"), std::string::npos) << r;
  EXPECT_NE(r.find("frames/sketch.png"), std::string::npos) << r;
  // nothing at all was removed, the run's own files included
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "frames" / "state_000001.kstate"));
  EXPECT_EQ(read_text(dir / "notes.txt"), "mine");
}

TEST(RunDirectory, SymbolicLinksAreNeverFollowed) {
  const fs::path root = test::temp_dir("rundir-links");
  put(root / "precious" / "photo.jpg", "keep");
  const fs::path dir = root / "run";
  fake_run(dir, false);
  // the run's frames/ replaced by a link to someone's folder
  fs::remove_all(dir / "frames");
  fs::create_directory_symlink(root / "precious", dir / "frames");
  const std::string r = refusal(dir.string(), true);
  EXPECT_NE(r.find("frames (a symbolic link)"), std::string::npos) << r;
  EXPECT_EQ(read_text(root / "precious" / "photo.jpg"), "keep");
  fs::remove(dir / "frames");
  // a link to a run directory is that directory
  fs::create_directory_symlink(dir, root / "link");
  EXPECT_NO_THROW(fake_run(root / "link", true));
  EXPECT_TRUE(fs::exists(dir / "frames" / "state_000001.kstate"));
  EXPECT_TRUE(fs::is_symlink(root / "link"));
  EXPECT_EQ(read_text(root / "precious" / "photo.jpg"), "keep");
}

TEST(RunDirectory, AMarkerCannotNameAnythingOutside) {
  const fs::path root = test::temp_dir("rundir-marker");
  put(root / "victim.txt", "keep");
  const fs::path dir = root / "run";
  fake_run(dir, false);
  std::ofstream(dir / RUN_MARKER, std::ios::app)
      << "\"../victim.txt\"\n\"" << (root / "victim.txt").string() << "\"\n\"\"\n";
  EXPECT_NO_THROW(fake_run(dir, true));
  EXPECT_EQ(read_text(root / "victim.txt"), "keep");
  // a marker that is not one leaves the directory alone
  std::ofstream(dir / RUN_MARKER, std::ios::trunc) << "my shopping list\n";
  const std::string r = refusal(dir.string(), true);
  EXPECT_NE(r.find("not a knitsim run marker"), std::string::npos) << r;
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
}

TEST(RunDirectory, EmptyNamesAndPlacesThatAreNeverRunDirectories) {
  EXPECT_NE(refusal("", true).find("empty"), std::string::npos);
  EXPECT_NE(refusal("/", true).find("refusing"), std::string::npos);
  const fs::path file = test::temp_dir("rundir-file") / "a.txt";
  put(file);
  EXPECT_NE(refusal(file.string(), true).find("not a directory"), std::string::npos);
  // an empty directory of the user's is fine, and becomes a run directory
  const fs::path empty = test::temp_dir("rundir-empty");
  EXPECT_NO_THROW(fake_run(empty, false));
}

TEST(RunDirectory, ARunDirectoryIsLockedWhileARunWritesIt) {
  const fs::path dir = test::temp_dir("rundir-lock") / "run";
  fake_run(dir, false);
  EXPECT_FALSE(locked(dir)) << "the lock outlived its run";
  const int fd = hold_elsewhere(dir);
  for (bool overwrite : {false, true}) {
    const std::string r = refusal(dir.string(), overwrite);
    EXPECT_NE(r.find("is writing into it"), std::string::npos) << r;
  }
  EXPECT_THROW(const RunDirectory d = continue_run_directory(dir.string()), std::invalid_argument);
  EXPECT_THROW(check_run_directory(dir.string(), true), std::invalid_argument);
  EXPECT_TRUE(fs::exists(dir / "summary.json")) << "a busy directory was touched";
  ::close(fd);
  {
    const RunDirectory d = prepare_run_directory(dir.string(), true);
    EXPECT_TRUE(locked(dir));
    // the same process opening it again shares the hold and changes nothing
    write_file_atomic((dir / "a.txt").string(), "a");
    const RunDirectory again = prepare_run_directory(dir.string(), true);
    EXPECT_TRUE(fs::exists(dir / "a.txt"));
  }
  EXPECT_FALSE(locked(dir));
}

TEST(RunDirectory, AKilledRunLeavesNoLock) {
  const fs::path dir = test::temp_dir("rundir-killed") / "run";
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  if (child == 0) {
    const RunDirectory d = prepare_run_directory(dir.string(), false);
    write_file_atomic((dir / "log.csv").string(), "t\n");
    const char c = 1;
    if (::write(ready[1], &c, 1) != 1) _exit(3);
    ::pause();  // killed here, holding the lock
    _exit(0);
  }
  char c = 0;
  ASSERT_EQ(::read(ready[0], &c, 1), 1);
  EXPECT_TRUE(locked(dir));
  EXPECT_NE(refusal(dir.string(), true).find("process " + std::to_string(child)),
            std::string::npos);
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  ::close(ready[0]);
  ::close(ready[1]);
  EXPECT_FALSE(locked(dir));
  // the killed run's files are its own: an overwrite takes them
  EXPECT_NO_THROW(fake_run(dir, true));
  EXPECT_FALSE(fs::exists(dir / "log.csv"));
}

TEST(RunDirectory, AScopeKeepsItsDirectoriesLockedToItsEnd) {
  const fs::path dir = test::temp_dir("rundir-scope") / "run";
  {
    const RunDirectoryScope scope;
    fake_run(dir, false);
    EXPECT_TRUE(locked(dir));
    // written after the run's own hold went, inside the scope: still named
    write_file_atomic((dir / "relaxed.kstate").string(), "r");
  }
  EXPECT_FALSE(locked(dir));
  EXPECT_NE(read_text(dir / RUN_MARKER).find("\"relaxed.kstate\""), std::string::npos);
  // a command writing into a free run directory (a render of its state) names its file too
  write_file_atomic((dir / "final.png").string(), "png");
  EXPECT_NE(read_text(dir / RUN_MARKER).find("\"final.png\""), std::string::npos);
  // but not into one another process is writing: the next overwrite then keeps it
  const int fd = hold_elsewhere(dir);
  write_file_atomic((dir / "export.obj").string(), "o");
  ::close(fd);
  EXPECT_NE(refusal(dir.string(), true).find("export.obj"), std::string::npos);
  fs::remove(dir / "export.obj");
  EXPECT_NO_THROW(fake_run(dir, true));
  EXPECT_FALSE(fs::exists(dir / "final.png"));
}

TEST(RunDirectory, ARunDirectoryInsideARunDirectoryGoesWithIt) {
  const fs::path dir = test::temp_dir("rundir-nested") / "run";
  fake_run(dir, false);
  fake_run(dir / "movie", false);  // a sequence rendered into the run's directory
  EXPECT_NO_THROW(fake_run(dir, true));
  EXPECT_FALSE(fs::exists(dir / "movie"));
  // one with a user's file in it stops the overwrite
  fake_run(dir / "movie", false);
  put(dir / "movie" / "keep.txt");
  EXPECT_NE(refusal(dir.string(), true).find("movie/keep.txt"), std::string::npos);
  fs::remove(dir / "movie" / "keep.txt");
  // and one being written is busy
  const int fd = hold_elsewhere(dir / "movie");
  EXPECT_NE(refusal(dir.string(), true).find("movie/ (another knitsim run"), std::string::npos);
  ::close(fd);
}

TEST(RunDirectory, ResumingInPlaceKeepsTheRunAndMarksAnOldDirectory) {
  const fs::path dir = test::temp_dir("rundir-continue") / "run";
  fake_run(dir, false);
  {
    const RunDirectory d = continue_run_directory(dir.string());
    write_file_atomic((dir / "frames" / "state_000002.kstate").string(), "s2");
  }
  EXPECT_TRUE(fs::exists(dir / "frames" / "state_000001.kstate"));
  EXPECT_NO_THROW(fake_run(dir, true));
  EXPECT_FALSE(fs::exists(dir / "frames" / "state_000002.kstate"));
  // a directory from before markers: resumed, it names only what is written from then on
  const fs::path old = test::temp_dir("rundir-old");
  put(old / "final.kstate", "old");
  {
    const RunDirectory d = continue_run_directory(old.string());
    write_file_atomic((old / "summary.json").string(), "{}");
  }
  const std::string r = refusal(old.string(), true);
  EXPECT_NE(r.find("final.kstate"), std::string::npos) << r;
  EXPECT_EQ(r.find("summary.json"), std::string::npos) << r;
  EXPECT_EQ(read_text(old / "final.kstate"), "old");
}

}  // namespace
}  // namespace knit
