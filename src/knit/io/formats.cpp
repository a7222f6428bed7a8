#include "knit/io/formats.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <stdexcept>

#include "knit/io/bcc.hpp"
#include "knit/io/tube_mesh.hpp"
#include "knit/util/atomic_file.hpp"
#include "knit/util/input_file.hpp"

namespace knit {

namespace {

std::string usd_bytes(const StateFile& s, const ExportOptions& o) {
  return usda_text({s}, {s.state.time}, o.objects);
}
std::string obj_bytes(const StateFile& s, const ExportOptions& o) {
  return obj_text(s, o.samples);
}
std::string bcc_bytes(const StateFile& s, const ExportOptions& o) {
  return bcc_text(s, o.samples);
}
std::string ply_state_bytes(const StateFile& s, const ExportOptions& o) {
  return ply_bytes(s, o.binary_ply, o.samples);
}
std::string vtp_bytes(const StateFile& s, const ExportOptions& o) {
  return vtp_text(s, o.samples);
}
std::string obj_mesh_bytes(const StateFile& s, const ExportOptions& o) {
  return obj_mesh_text(tube_mesh(s, o.samples, o.sides));
}
std::string ply_mesh_state_bytes(const StateFile& s, const ExportOptions& o) {
  return ply_mesh_bytes(tube_mesh(s, o.samples, o.sides));
}
std::string glb_state_bytes(const StateFile& s, const ExportOptions& o) {
  return glb_bytes(tube_mesh(s, o.samples, o.sides));
}

std::string lower_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace

const std::vector<FileFormat>& file_formats() {
  static const std::vector<FileFormat> formats = {
      {"usd",
       {".usda", ".usd"},
       "exact B-spline curves (USD text; a sequence time-sampled)",
       usd_bytes,
       nullptr},
      {"obj", {".obj"}, "sampled centrelines as polylines", obj_bytes, parse_obj},
      {"bcc", {".bcc"}, "sampled centrelines (binary curve collection)", bcc_bytes, parse_bcc},
      {"ply", {".ply"}, "sampled centrelines as points and edges", ply_state_bytes, nullptr},
      {"vtp",
       {".vtp"},
       "sampled centrelines with per-point radius, yarn, row, column, velocity (ParaView)",
       vtp_bytes,
       nullptr},
      {"obj-mesh", {".obj"}, "yarn tubes as triangles", obj_mesh_bytes, nullptr},
      {"ply-mesh", {".ply"}, "yarn tubes as triangles", ply_mesh_state_bytes, nullptr},
      {"glb",
       {".glb"},
       "yarn tubes as triangles (glTF binary, metres, Y up)",
       glb_state_bytes,
       nullptr},
      {"yarns",
       {".yarns"},
       "yarn polylines with radii (textiles-lab smobj)",
       nullptr,
       parse_yarns_file},
  };
  return formats;
}

const FileFormat& export_format(const std::string& name) {
  for (const FileFormat& f : file_formats())
    if (f.write && name == f.name) return f;
  std::string known;
  for (const FileFormat& f : file_formats())
    if (f.write) known += (known.empty() ? "" : ", ") + std::string(f.name);
  throw std::invalid_argument("unknown export format '" + name + "' (known: " + known + ")");
}

const FileFormat* import_format(const std::string& path) {
  const std::string ext = lower_extension(path);
  for (const FileFormat& f : file_formats())
    if (f.read && std::find(f.extensions.begin(), f.extensions.end(), ext) != f.extensions.end())
      return &f;
  return nullptr;
}

std::string export_format_list() {
  std::string list;
  for (const FileFormat& f : file_formats())
    if (f.write)
      list += (list.empty() ? "" : ", ") + std::string(f.name) + " (" + f.description + ")";
  return list;
}

const std::vector<std::string>& export_formats() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> n;
    for (const FileFormat& f : file_formats())
      if (f.write) n.push_back(f.name);
    return n;
  }();
  return names;
}

std::string export_extension(const std::string& format) {
  return export_format(format).extensions.front();
}

void export_state(const StateFile& s, const std::string& format, const std::string& path,
                  const ExportOptions& o) {
  write_file_atomic(path, export_format(format).write(s, o));
}

bool is_importable(const std::string& path) {
  return import_format(path) != nullptr;
}

std::vector<RawYarn> read_raw_yarns(const std::string& path) {
  // what the path is (missing, a directory, a device) comes before what it is called
  check_input_path(path, "yarn geometry file");
  const FileFormat* format = import_format(path);
  if (!format) {
    std::string known;
    std::vector<std::string> exts;
    for (const FileFormat& f : file_formats())
      if (f.read) exts.insert(exts.end(), f.extensions.begin(), f.extensions.end());
    for (size_t k = 0; k < exts.size(); ++k)
      known += (k == 0 ? "" : k + 1 == exts.size() ? " or " : ", ") + exts[k];
    throw std::runtime_error(path + ": unknown yarn file type '" + lower_extension(path) +
                             "' (expected " + known + ")");
  }
  return format->read(read_yarn_file(path), path);
}

}  // namespace knit
