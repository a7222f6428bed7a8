#pragma once
// Writing a file so that it is never seen half-written: every output of knitsim goes
// through here.
#include <string>

namespace knit {

/// Writes `contents` to `path` atomically (PATH.tmp, then a rename over PATH). Where PATH
/// lies in a run directory, its marker names PATH first (claim_run_output, run_dir.hpp),
/// so that --overwrite may remove it later. Throws std::runtime_error naming PATH on
/// failure, leaving no PATH.tmp behind.
void write_file_atomic(const std::string& path, const std::string& contents);

}  // namespace knit
