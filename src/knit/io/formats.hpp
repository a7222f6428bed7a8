#pragma once
// The file formats knitsim writes and reads, in one registry: each format's name, the
// extensions it goes by, one line on what it holds, and its writer and reader. The export
// command and its help, the run commands' --export, the importers and the Python module
// all list and dispatch through it; adding a format is one entry here and its writer or
// reader (export.hpp, tube_mesh.hpp, import.hpp).
#include <string>
#include <string_view>
#include <vector>

#include "knit/io/export.hpp"
#include "knit/io/import.hpp"

namespace knit {

struct FileFormat {
  const char* name;  ///< as --format takes it: "usd", "obj", "obj-mesh", …
  /// the extensions it goes by, lower case; the first is the one written
  std::vector<std::string> extensions;
  const char* description;  ///< one line, for help texts and docs
  /// one state's file, its bytes (null: knitsim does not write the format)
  std::string (*write)(const StateFile& state, const ExportOptions& options);
  /// a file's yarn polylines, in its own units (null: knitsim does not read it)
  std::vector<RawYarn> (*read)(std::string_view data, const std::string& name);
};

/// Every format, writers first in the order --format lists them.
const std::vector<FileFormat>& file_formats();

/// The format named `name` that knitsim writes; throws std::invalid_argument listing them.
const FileFormat& export_format(const std::string& name);

/// The format knitsim reads files with `path`'s extension in (case-insensitive), or null.
const FileFormat* import_format(const std::string& path);

/// "name (description), …" of every written format: the one list help texts show.
std::string export_format_list();

}  // namespace knit
