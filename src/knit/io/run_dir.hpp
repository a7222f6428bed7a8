#pragma once
// Run directories are never mixed: a run writes into an empty (or new) directory, or,
// when told to overwrite, into one it has emptied first.
#include <string>

namespace knit {

/// Makes `dir` ready for a run's outputs: creates it when missing; when it already holds
/// files, throws std::invalid_argument naming a few of them unless `overwrite`, which
/// removes them first. Always refuses "/", the home directory and a repository's root
/// (a directory holding .git), and a path that is not a directory.
void prepare_run_directory(const std::string& dir, bool overwrite);

/// True when `state_file` lies in the run directory `dir` (DIR/ or DIR/frames/): a run
/// resumed from it goes on in that directory rather than starting a new one.
bool resumes_in_place(const std::string& state_file, const std::string& dir);

/// The checks of prepare_run_directory without touching anything: throws when `dir` could
/// not be prepared (a long job checks this before it starts).
void check_run_directory(const std::string& dir, bool overwrite);

}  // namespace knit
