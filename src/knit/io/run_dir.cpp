#include "knit/io/run_dir.hpp"

#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace knit {

namespace {

// the checks; with `act`, also creates or empties the directory
void run_directory(const std::string& dir, bool overwrite, bool act) {
  namespace fs = std::filesystem;
  if (dir.empty()) throw std::invalid_argument("--out: no output directory given");
  const fs::path p(dir);
  std::error_code ec;
  const fs::path canon = fs::weakly_canonical(p, ec);
  const fs::path real = ec ? p : canon;
  if (real == real.root_path())
    throw std::invalid_argument("--out " + dir +
                                ": refusing to write a run into the root directory");
  if (const char* home = std::getenv("HOME"); home && *home) {
    const fs::path h = fs::weakly_canonical(fs::path(home), ec);
    if (!ec && real == h)
      throw std::invalid_argument("--out " + dir +
                                  ": refusing to write a run into the home directory");
  }
  if (fs::exists(p / ".git"))
    throw std::invalid_argument("--out " + dir +
                                ": refusing to write a run into a repository's root");
  if (!fs::exists(p)) {
    if (act) fs::create_directories(p);
    return;
  }
  if (!fs::is_directory(p))
    throw std::invalid_argument("--out " + dir + ": exists and is not a directory");
  std::vector<fs::path> entries;
  for (const auto& e : fs::directory_iterator(p)) entries.push_back(e.path());
  if (entries.empty()) return;
  if (!overwrite) {
    std::string names;
    for (size_t k = 0; k < entries.size() && k < 3; ++k)
      names += (k ? ", " : "") + entries[k].filename().string();
    if (entries.size() > 3) names += ", …";
    throw std::invalid_argument("--out " + dir + ": the directory already holds files (" + names +
                                "); give --overwrite to replace them, or choose another directory");
  }
  if (act)
    for (const fs::path& e : entries) fs::remove_all(e);
}

}  // namespace

void prepare_run_directory(const std::string& dir, bool overwrite) {
  run_directory(dir, overwrite, true);
}

bool resumes_in_place(const std::string& state_file, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (state_file.empty() || dir.empty() || !fs::is_directory(dir, ec)) return false;
  const fs::path d = fs::canonical(dir, ec);
  if (ec) return false;
  const fs::path parent = fs::canonical(fs::absolute(state_file).parent_path(), ec);
  if (ec) return false;
  return parent == d || parent == d / "frames";
}

void check_run_directory(const std::string& dir, bool overwrite) {
  run_directory(dir, overwrite, false);
}

}  // namespace knit
