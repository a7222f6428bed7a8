#include "knit/util/run_dir.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <vector>

namespace knit {

namespace fs = std::filesystem;

namespace detail {

struct HeldRunDirectory {
  fs::path dir;                   // canonical
  int fd = -1;                    // the marker, open for appending, flock'd
  std::set<std::string> claimed;  // relative paths, '/'-separated
  HeldRunDirectory() = default;
  HeldRunDirectory(const HeldRunDirectory&) = delete;
  HeldRunDirectory& operator=(const HeldRunDirectory&) = delete;
  ~HeldRunDirectory() {
    if (fd >= 0) ::close(fd);  // releases the lock
  }
};

}  // namespace detail

namespace {

using Held = detail::HeldRunDirectory;

constexpr const char* MAGIC = "knitsim run directory 1";

struct Registry {
  std::mutex mutex;
  std::map<fs::path, std::weak_ptr<Held>> held;
  int scopes = 0;
  std::vector<std::shared_ptr<Held>> pinned;  // kept by the scopes
};

Registry& registry() {
  static Registry r;
  return r;
}

// `dir` made absolute, its symlinks and `..` resolved as far as it exists, no trailing '/'
fs::path resolve(const std::string& dir) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(dir), ec);
  if (ec) p = fs::absolute(dir).lexically_normal();
  if (!p.has_filename() && p != p.root_path()) p = p.parent_path();
  return p;
}

std::string describe(const std::string& dir, const fs::path& real) {
  return real.string() == dir ? dir : dir + " (" + real.string() + ")";
}

// the process that opens a directory: the marker's second line, and the busy message's source
std::string owner_line() {
  nlohmann::json j;
  j["pid"] = static_cast<long long>(::getpid());
  const std::time_t now = std::time(nullptr);
  char when[32];
  std::strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  j["since"] = when;
  std::ifstream cmd("/proc/self/cmdline", std::ios::binary);
  std::string args((std::istreambuf_iterator<char>(cmd)), std::istreambuf_iterator<char>());
  std::replace(args.begin(), args.end(), '\0', ' ');
  while (!args.empty() && args.back() == ' ') args.pop_back();
  if (args.size() > 300) args = args.substr(0, 300) + "…";
  j["command"] = args;
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::string read_all(int fd) {
  std::string s;
  char buf[8192];
  off_t at = 0;
  for (;;) {
    const ssize_t n = ::pread(fd, buf, sizeof buf, at);
    if (n <= 0) break;
    s.append(buf, static_cast<size_t>(n));
    at += n;
  }
  return s;
}

struct Marker {
  bool valid = false;
  nlohmann::json owner;
  std::set<std::string> paths;
};

// A relative path inside the directory, or "" for one a marker must not name (absolute,
// leading out with "..", or empty): a marker edited by hand can never reach outside.
std::string inside(const std::string& rel) {
  const fs::path p = fs::path(rel).lexically_normal();
  if (p.empty() || p.is_absolute() || p.has_root_name()) return "";
  for (const auto& part : p)
    if (part == "..") return "";
  std::string s = p.generic_string();
  while (!s.empty() && s.back() == '/') s.pop_back();
  return s == "." ? "" : s;
}

Marker parse_marker(const std::string& text) {
  Marker m;
  size_t at = 0;
  int line = 0;
  while (at < text.size()) {
    size_t end = text.find('\n', at);
    const bool whole = end != std::string::npos;  // a last line cut short by a kill is skipped
    if (!whole) end = text.size();
    const std::string l = text.substr(at, end - at);
    at = end + 1;
    ++line;
    if (line == 1) {
      m.valid = whole && l == MAGIC;
      if (!m.valid) return m;
      continue;
    }
    if (!whole) break;
    const nlohmann::json j = nlohmann::json::parse(l, nullptr, false);
    if (line == 2) {
      if (j.is_object()) m.owner = j;
      continue;
    }
    if (j.is_string())
      if (std::string rel = inside(j.get<std::string>()); !rel.empty()) m.paths.insert(rel);
  }
  return m;
}

void write_line(int fd, const std::string& line) {
  const std::string l = line + "\n";
  size_t done = 0;
  while (done < l.size()) {
    const ssize_t n = ::write(fd, l.data() + done, l.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0)
      throw std::runtime_error(std::string("cannot write the run marker: ") + std::strerror(errno));
    done += static_cast<size_t>(n);
  }
}

// the marker anew: this process as its owner, `paths` as what runs wrote
void rewrite_marker(int fd, const std::set<std::string>& paths) {
  if (::ftruncate(fd, 0) != 0)
    throw std::runtime_error(std::string("cannot rewrite the run marker: ") + std::strerror(errno));
  std::string text = std::string(MAGIC) + "\n" + owner_line() + "\n";
  for (const std::string& p : paths) text += nlohmann::json(p).dump() + "\n";
  write_line(fd, text.substr(0, text.size() - 1));
}

std::string busy_message(const std::string& what, const Marker& m) {
  std::string who = "another knitsim run";
  if (m.owner.is_object()) {
    if (m.owner.contains("pid") && m.owner["pid"].is_number_integer())
      who += " (process " + std::to_string(m.owner["pid"].get<long long>());
    else
      who += " (";
    if (m.owner.contains("since") && m.owner["since"].is_string())
      who += ", since " + m.owner["since"].get<std::string>();
    if (m.owner.contains("command") && m.owner["command"].is_string() &&
        !m.owner["command"].get<std::string>().empty())
      who += ": " + m.owner["command"].get<std::string>();
    who += ")";
  }
  return "run directory " + what + ": " + who +
         " is writing into it; wait for it to end, or choose another directory";
}

// What a directory holds, sorted by whose it is.
struct Survey {
  std::vector<std::string> own_files, own_dirs;  // relative
  std::vector<std::string> foreign;              // relative, as shown to the user
  size_t entries = 0;                            // top-level entries besides the marker
};

Survey survey(const fs::path& root, const std::set<std::string>& claimed);

// A folder inside a run directory that is a run directory of its own (a sequence rendered
// into DIR/movie): its own marker says what is whose. One being written is not removable.
bool nested_run(const fs::path& root, const std::string& key, Survey& s) {
  const fs::path sub = root / key;
  const int fd = ::open((sub / RUN_MARKER).c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return false;
  const Marker m = parse_marker(read_all(fd));
  const bool busy = ::flock(fd, LOCK_SH | LOCK_NB) != 0;
  ::close(fd);
  if (!m.valid) return false;
  if (busy) {
    s.foreign.push_back(key + "/ (another knitsim run is writing it)");
    return true;
  }
  const Survey inner = survey(sub, m.paths);
  s.own_dirs.push_back(key);
  s.own_files.push_back(key + "/" + RUN_MARKER);
  for (const std::string& f : inner.own_files) s.own_files.push_back(key + "/" + f);
  for (const std::string& d : inner.own_dirs) s.own_dirs.push_back(key + "/" + d);
  for (const std::string& f : inner.foreign) s.foreign.push_back(key + "/" + f);
  return true;
}

void visit(const fs::path& root, const std::string& rel, const std::set<std::string>& claimed,
           const std::set<std::string>& ancestors, Survey& s) {
  std::error_code ec;
  fs::directory_iterator it(rel.empty() ? root : root / rel, ec), end;
  if (ec) {
    s.foreign.push_back((rel.empty() ? "." : rel) + "/ (unreadable: " + ec.message() + ")");
    return;
  }
  for (; it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (rel.empty() && name == RUN_MARKER) continue;
    if (rel.empty()) ++s.entries;
    const std::string key = rel.empty() ? name : rel + "/" + name;
    const fs::file_status st = it->symlink_status(ec);
    if (fs::is_symlink(st)) {
      s.foreign.push_back(key + " (a symbolic link)");
    } else if (fs::is_directory(st)) {
      if (claimed.count(key) || ancestors.count(key)) {
        s.own_dirs.push_back(key);
        visit(root, key, claimed, ancestors, s);
      } else if (!nested_run(root, key, s)) {
        s.foreign.push_back(key + "/");
      }
    } else if (fs::is_regular_file(st)) {
      const bool tmp = key.size() > 4 && key.compare(key.size() - 4, 4, ".tmp") == 0;
      if (claimed.count(key) || (tmp && claimed.count(key.substr(0, key.size() - 4))))
        s.own_files.push_back(key);
      else
        s.foreign.push_back(key);
    } else {
      s.foreign.push_back(key + " (not a regular file)");
    }
  }
  if (ec) s.foreign.push_back((rel.empty() ? "." : rel) + "/ (unreadable: " + ec.message() + ")");
}

Survey survey(const fs::path& root, const std::set<std::string>& claimed) {
  std::set<std::string> ancestors;
  for (const std::string& c : claimed)
    for (fs::path p = fs::path(c).parent_path(); !p.empty(); p = p.parent_path())
      ancestors.insert(p.generic_string());
  Survey s;
  visit(root, "", claimed, ancestors, s);
  return s;
}

// A file a knitsim command writes into a run directory no run holds (a render of its final
// state, an export): named in its marker while the directory is free, as the run's outputs
// are. One a run is writing is left unnamed (a later --overwrite then keeps it).
void claim_in_free_directory(const fs::path& full) {
  int depth = 0;
  for (fs::path dir = full.parent_path(); depth < 16 && dir.has_relative_path();
       dir = dir.parent_path(), ++depth) {
    const int fd = ::open((dir / RUN_MARKER).c_str(), O_RDWR | O_APPEND | O_CLOEXEC | O_NOFOLLOW);
    if (fd < 0) continue;
    if (::flock(fd, LOCK_EX | LOCK_NB) == 0) {
      const Marker m = parse_marker(read_all(fd));
      const std::string rel = inside(full.lexically_relative(dir).generic_string());
      if (m.valid && !rel.empty() && !m.paths.count(rel)) {
        try {
          write_line(fd, nlohmann::json(rel).dump());
        } catch (const std::exception&) {
        }
      }
    }
    ::close(fd);
    return;
  }
}

std::string some(const std::vector<std::string>& names) {
  std::string out;
  for (size_t k = 0; k < names.size() && k < 3; ++k) out += (k ? ", " : "") + names[k];
  if (names.size() > 3) out += ", … " + std::to_string(names.size()) + " in all";
  return out;
}

std::vector<std::string> top_level(const fs::path& root) {
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(root, ec), end; !ec && it != end; it.increment(ec)) {
    std::string n = it->path().filename().string();
    if (it->is_directory(ec) && !it->is_symlink(ec)) n += "/";
    names.push_back(n);
  }
  std::sort(names.begin(), names.end());
  return names;
}

void refuse_foreign(const std::string& what, const Survey& s) {
  throw std::invalid_argument(
      "run directory " + what + " holds files no knitsim run wrote (" + some(s.foreign) +
      "); knitsim removes only a run's own files (those its marker " + RUN_MARKER +
      " names): move the others away, or choose another directory");
}

[[noreturn]] void refuse_unmarked(const std::string& what, const std::vector<std::string>& names) {
  throw std::invalid_argument(
      "run directory " + what + " already holds files (" + some(names) +
      ") and no knitsim run marker (" + RUN_MARKER +
      "): they are not a knitsim run's (or are a run's from before markers), and knitsim "
      "removes only files its runs wrote; move them away, or choose another directory");
}

// The checks every way in shares: a name, not a place knitsim must never write a run into.
fs::path checked_path(const std::string& dir) {
  if (dir.empty())
    throw std::invalid_argument("run directory: the name is empty; give a directory (--out DIR)");
  const fs::path real = resolve(dir);
  const std::string what = describe(dir, real);
  if (real == real.root_path())
    throw std::invalid_argument("run directory " + what +
                                ": refusing to write a run into the root directory");
  if (const char* home = std::getenv("HOME"); home && *home)
    if (real == resolve(home))
      throw std::invalid_argument("run directory " + what +
                                  ": refusing to write a run into the home directory");
  std::error_code ec;
  if (fs::exists(real / ".git", ec))
    throw std::invalid_argument("run directory " + what +
                                ": refusing to write a run into a repository's root");
  const fs::file_status st = fs::status(real, ec);
  if (fs::exists(st) && !fs::is_directory(st))
    throw std::invalid_argument("run directory " + what + ": exists and is not a directory");
  return real;
}

enum class Mode { NEW_RUN, CONTINUE, CHECK };

}  // namespace

std::string RunDirectory::path() const {
  return held_ ? held_->dir.string() : std::string();
}

RunDirectory open_run_directory(const std::string& dir, bool overwrite, bool continuing) {
  const Mode mode = continuing ? Mode::CONTINUE : Mode::NEW_RUN;
  const fs::path real = checked_path(dir);
  const std::string what = describe(dir, real);
  Registry& reg = registry();
  std::lock_guard<std::mutex> guard(reg.mutex);
  RunDirectory out;
  if (auto it = reg.held.find(real); it != reg.held.end())
    if (std::shared_ptr<Held> h = it->second.lock()) {
      out.held_ = h;  // this process writes it already
      return out;
    }
  std::error_code ec;
  const fs::path marker = real / RUN_MARKER;
  const bool existed = fs::is_directory(real, ec);
  const bool marked = existed && fs::exists(fs::symlink_status(marker, ec));
  if (existed && fs::is_symlink(fs::symlink_status(marker, ec)))
    throw std::invalid_argument("run directory " + what + ": its " + RUN_MARKER +
                                " is a symbolic link, not a knitsim run marker");
  if (existed && !marked && mode == Mode::NEW_RUN) {
    const std::vector<std::string> names = top_level(real);
    if (!names.empty()) refuse_unmarked(what, names);
  }
  if (!existed) {
    fs::create_directories(real, ec);
    if (ec && !fs::is_directory(real))
      throw std::runtime_error("run directory " + what + ": cannot create it: " + ec.message());
  }
  auto held = std::make_shared<Held>();
  held->dir = real;
  held->fd = ::open(marker.c_str(), O_RDWR | O_CREAT | O_APPEND | O_CLOEXEC | O_NOFOLLOW, 0644);
  if (held->fd < 0)
    throw std::runtime_error("run directory " + what + ": cannot open " + RUN_MARKER + ": " +
                             std::strerror(errno));
  if (::flock(held->fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const Marker m = parse_marker(read_all(held->fd));
    if (err == EWOULDBLOCK) throw std::invalid_argument(busy_message(what, m));
    throw std::runtime_error("run directory " + what + ": cannot lock " + RUN_MARKER + ": " +
                             std::strerror(err));
  }
  const std::string text = read_all(held->fd);
  Marker m = parse_marker(text);
  if (!m.valid && !text.empty())
    throw std::invalid_argument("run directory " + what + ": its " + RUN_MARKER +
                                " is not a knitsim run marker; knitsim leaves the directory alone");
  if (mode == Mode::NEW_RUN) {
    const Survey s = survey(real, m.paths);
    if (!s.foreign.empty()) refuse_foreign(what, s);
    if (s.entries > 0 && !overwrite) {
      std::vector<std::string> mine = top_level(real);
      mine.erase(std::remove(mine.begin(), mine.end(), RUN_MARKER), mine.end());
      throw std::invalid_argument("run directory " + what +
                                  " already holds an earlier run's files (" + some(mine) +
                                  "); give --overwrite to replace them, or choose another "
                                  "directory");
    }
    for (const std::string& f : s.own_files) {
      fs::remove(real / f, ec);
      if (ec)
        throw std::runtime_error("run directory " + what + ": cannot remove the earlier run's " +
                                 f + ": " + ec.message());
    }
    // the folders that held them, deepest first (one left holding anything stays)
    std::vector<std::string> dirs = s.own_dirs;
    std::sort(dirs.begin(), dirs.end(), [](const std::string& a, const std::string& b) {
      return std::count(a.begin(), a.end(), '/') > std::count(b.begin(), b.end(), '/');
    });
    for (const std::string& d : dirs) fs::remove(real / d, ec);
    m.paths.clear();
  }
  rewrite_marker(held->fd, m.paths);
  held->claimed = std::move(m.paths);
  reg.held[real] = held;
  if (reg.scopes > 0) reg.pinned.push_back(held);
  out.held_ = std::move(held);
  return out;
}

RunDirectory prepare_run_directory(const std::string& dir, bool overwrite) {
  return open_run_directory(dir, overwrite, false);
}

RunDirectory continue_run_directory(const std::string& dir) {
  return open_run_directory(dir, false, true);
}

void check_run_directory(const std::string& dir, bool overwrite) {
  const fs::path real = checked_path(dir);
  const std::string what = describe(dir, real);
  std::error_code ec;
  if (!fs::is_directory(real, ec)) return;
  {
    Registry& reg = registry();
    std::lock_guard<std::mutex> guard(reg.mutex);
    if (auto it = reg.held.find(real); it != reg.held.end() && !it->second.expired()) return;
  }
  const fs::path marker = real / RUN_MARKER;
  if (!fs::exists(fs::symlink_status(marker, ec))) {
    const std::vector<std::string> names = top_level(real);
    if (!names.empty()) refuse_unmarked(what, names);
    return;
  }
  const int fd = ::open(marker.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0)
    throw std::invalid_argument("run directory " + what + ": cannot read " + RUN_MARKER + ": " +
                                std::strerror(errno));
  const Marker m = parse_marker(read_all(fd));
  const bool busy = ::flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
  ::close(fd);
  if (busy) throw std::invalid_argument(busy_message(what, m));
  if (!m.valid)
    throw std::invalid_argument("run directory " + what + ": its " + RUN_MARKER +
                                " is not a knitsim run marker; knitsim leaves the directory alone");
  const Survey s = survey(real, m.paths);
  if (!s.foreign.empty()) refuse_foreign(what, s);
  if (s.entries > 0 && !overwrite)
    throw std::invalid_argument("run directory " + what +
                                " already holds an earlier run's files; give --overwrite to "
                                "replace them, or choose another directory");
}

void claim_run_output(const std::string& path) {
  if (path.empty()) return;
  Registry& reg = registry();
  std::lock_guard<std::mutex> guard(reg.mutex);
  std::error_code ec;
  const fs::path abs = fs::absolute(path, ec).lexically_normal();
  if (ec) return;
  fs::path parent = abs.has_filename() ? abs.parent_path() : abs.parent_path().parent_path();
  const fs::path name = abs.has_filename() ? abs.filename() : abs.parent_path().filename();
  const fs::path canon = fs::weakly_canonical(parent, ec);
  if (!ec) parent = canon;
  if (!parent.has_filename() && parent != parent.root_path()) parent = parent.parent_path();
  const fs::path full = parent / name;
  // the innermost directory held that contains it
  std::shared_ptr<Held> owner;
  std::string rel;
  for (auto it = reg.held.begin(); it != reg.held.end();) {
    std::shared_ptr<Held> h = it->second.lock();
    if (!h) {
      it = reg.held.erase(it);
      continue;
    }
    ++it;
    const std::string r = inside(full.lexically_relative(h->dir).generic_string());
    if (!r.empty() && (!owner || h->dir.string().size() > owner->dir.string().size())) {
      owner = h;
      rel = r;
    }
  }
  if (!owner) {
    claim_in_free_directory(full);
    return;
  }
  if (!owner->claimed.insert(rel).second) return;
  try {
    write_line(owner->fd, nlohmann::json(rel).dump());
  } catch (const std::exception&) {
    // a marker that cannot grow (a full disk) leaves the file unnamed: a later --overwrite
    // then refuses to remove it, which loses nothing
  }
}

RunDirectoryScope::RunDirectoryScope() {
  std::lock_guard<std::mutex> guard(registry().mutex);
  ++registry().scopes;
}

RunDirectoryScope::~RunDirectoryScope() {
  std::vector<std::shared_ptr<Held>> release;
  {
    std::lock_guard<std::mutex> guard(registry().mutex);
    if (--registry().scopes == 0) release.swap(registry().pinned);
  }
  // released outside the registry's lock: the last reference closes the marker
}

bool resumes_in_place(const std::string& state_file, const std::string& dir) {
  std::error_code ec;
  if (state_file.empty() || dir.empty() || !fs::is_directory(dir, ec)) return false;
  const fs::path d = fs::canonical(dir, ec);
  if (ec) return false;
  const fs::path parent = fs::canonical(fs::absolute(state_file).parent_path(), ec);
  if (ec) return false;
  return parent == d || parent == d / "frames";
}

}  // namespace knit
