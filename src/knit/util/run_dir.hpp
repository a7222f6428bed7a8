#pragma once
// Run directories: a run writes into a new or empty directory, or into one that holds only
// files knitsim runs wrote there, which --overwrite removes first. Nothing else is ever
// deleted.
//
// Each run directory holds a marker, DIR/.knitsim-run: its first line names the format, its
// second (JSON) the process that last opened it, and every further line (a JSON string) one
// path, relative to DIR, that a knitsim run wrote there (a file or a folder it made). A
// file the marker names also owns its temporary sibling NAME.tmp (an atomic write cut short).
// --overwrite deletes exactly what the marker names and the folders that held them; an
// entry it does not name (a user's file, a symlink, a folder of someone else's files) or a
// directory without a marker (someone else's, or a run from before markers) makes it refuse,
// naming what it found.
//
// While a run writes a directory it holds an exclusive OS lock (flock) on the marker: a second
// run into the same directory is refused, naming the process that holds it; the lock dies
// with its process, so a killed run never leaves a directory locked.
#include <memory>
#include <string>
#include "knit/util/atomic_file.hpp"

namespace knit {

/// The marker's name inside a run directory.
inline constexpr const char* RUN_MARKER = ".knitsim-run";

namespace detail {
struct HeldRunDirectory;
}

/// A run directory this process holds (locked). Copies share the hold; the lock is released
/// when the last copy goes (or, inside a RunDirectoryScope, when that scope ends).
class RunDirectory {
 public:
  RunDirectory() = default;
  explicit operator bool() const { return static_cast<bool>(held_); }
  /// The directory, canonical; empty when none is held.
  std::string path() const;

 private:
  friend RunDirectory open_run_directory(const std::string&, bool, bool);
  std::shared_ptr<detail::HeldRunDirectory> held_;
};

/// Makes `dir` ready for a new run and locks it: creates it when missing; when it already
/// holds an earlier run's files, throws std::invalid_argument naming a few of them unless
/// `overwrite`, which removes them (only those: see above). Always refuses an empty name,
/// "/", the home directory, a repository's root (a folder holding .git), a path that is not
/// a directory, a directory another process is writing, and one holding anything no knitsim
/// run wrote. Where this process holds `dir` already, returns that hold and changes nothing.
[[nodiscard]] RunDirectory prepare_run_directory(const std::string& dir, bool overwrite);

/// Locks the run directory `dir` to go on with the run in it (a resume in place): nothing is
/// removed; a directory from before markers gets one, naming only what is written from now.
[[nodiscard]] RunDirectory continue_run_directory(const std::string& dir);

/// The checks of prepare_run_directory without touching anything: throws when `dir` could
/// not be prepared now (a long job checks this before it starts).
void check_run_directory(const std::string& dir, bool overwrite);

/// Records `path` (a file or folder about to be written, or just made) in the marker of the
/// run directory this process holds that contains it; does nothing for a path in none. Every
/// writer of a run's outputs calls it (write_file_atomic does).
void claim_run_output(const std::string& path);

/// While one lives, every run directory this process opens stays locked until the scope ends
/// (the command line's whole command: a recipe's outputs, then the command's own).
class RunDirectoryScope {
 public:
  RunDirectoryScope();
  ~RunDirectoryScope();
  RunDirectoryScope(const RunDirectoryScope&) = delete;
  RunDirectoryScope& operator=(const RunDirectoryScope&) = delete;
};

/// True when `state_file` lies in the run directory `dir` (DIR/ or DIR/frames/): a run
/// resumed from it goes on in that directory rather than starting a new one.
bool resumes_in_place(const std::string& state_file, const std::string& dir);

}  // namespace knit
