#include "knit/present/plot.hpp"

#include <stdlib.h>
#include <cctype>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "knit/io/state_file.hpp"
#include "knit/util/atomic_file.hpp"
#include "knit/util/input_file.hpp"
#include "knit/util/process.hpp"
#include "knit/util/run_dir.hpp"

namespace knit {
namespace fs = std::filesystem;
namespace {

// a gnuplot single-quoted string
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

std::string number(double v) {
  if (!std::isfinite(v)) return "NaN";
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

// writes the table as whitespace-separated numbers gnuplot reads without any parsing doubts
void write_data(const CsvTable& t, const std::string& path) {
  std::string out;
  for (const auto& row : t.rows) {
    for (size_t c = 0; c < row.size(); ++c) {
      if (c) out += ' ';
      out += number(row[c]);
    }
    out += '\n';
  }
  write_file_atomic(path, out);
}

// runs `gnuplot script`; throws with gnuplot's own messages on failure
void run_gnuplot(const std::string& gnuplot, const std::string& script, const std::string& what) {
  std::string messages;
  const int rc = run_process({gnuplot, script}, messages);
  if (rc == 0) return;
  while (!messages.empty() && std::isspace(static_cast<unsigned char>(messages.back())))
    messages.pop_back();
  if (messages.size() > 1000) messages = messages.substr(0, 1000) + "…";
  const std::string status = rc > 128 ? "killed by signal " + std::to_string(rc - 128)
                                      : "exit status " + std::to_string(rc);
  throw std::runtime_error(what + ": gnuplot failed (" + status + ")" +
                           (messages.empty() ? std::string(", with no message") : ": " + messages));
}

// a temporary working folder removed on scope exit
struct TempDir {
  fs::path path;
  explicit TempDir(const fs::path& near) {
    std::string tmpl = (fs::temp_directory_path() / "knitsim-plot-XXXXXX").string();
    if (!mkdtemp(tmpl.data()))
      throw std::runtime_error(near.string() + ": cannot create a temporary folder");
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

const char* PREAMBLE =
    "set terminal pngcairo size 900,540 enhanced font 'sans,11' linewidth 1.5\n"
    "set grid lc rgb '#dddddd'\nset key below\nset border lc rgb '#555555'\n"
    "set style line 1 lc rgb '#2f7074' lw 2\nset style line 2 lc rgb '#b4533c' lw 2\n"
    "set style line 3 lc rgb '#d4a03f' lw 2\nset style line 4 lc rgb '#77506f' lw 2\n"
    "set style line 5 lc rgb '#4a6183' lw 2\nset style line 6 lc rgb '#8ba57c' lw 2\n";

// one plot: `body` draws it, the PNG goes to `out` through a temporary name
std::string plot_script(const std::string& out_tmp, const std::string& title,
                        const std::string& body) {
  std::string s = PREAMBLE;
  s += "set output " + quoted(out_tmp) + "\n";
  s += "set title " + quoted(title) + " noenhanced\n";
  s += body;
  s += "unset output\n";
  return s;
}

void render_plot(const std::string& gnuplot, const TempDir& tmp, const std::string& out,
                 const std::string& title, const std::string& body) {
  const std::string out_tmp = out + ".tmp";
  claim_run_output(out);  // and so out_tmp
  const std::string script = (tmp.path / (fs::path(out).stem().string() + ".gp")).string();
  write_file_atomic(script, plot_script(out_tmp, title, body));
  try {
    run_gnuplot(gnuplot, script, out);
  } catch (...) {
    std::error_code ec;
    fs::remove(out_tmp, ec);
    throw;
  }
  std::error_code ec;
  fs::rename(out_tmp, out, ec);
  if (ec) throw std::runtime_error(out + ": cannot rename the plot into place: " + ec.message());
}

bool all_positive(const CsvTable& t, int col) {
  bool any = false;
  for (const auto& r : t.rows) {
    if (!std::isfinite(r[col])) continue;
    if (r[col] <= 0) return false;
    any = true;
  }
  return any;
}

}  // namespace

void check_plot_path(const std::string& path, const std::string& option) {
  std::string ext = fs::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png") return;
  throw std::invalid_argument((option.empty() ? "" : option + " ") + printable(path, 200) +
                              ": plots are written as PNG images: name it .png");
}

std::string axis_label(const std::string& column) {
  static const std::map<std::string, std::string> units = {
      {"cm", "cm"}, {"mm", "mm"},   {"m", "m"},     {"s", "s"},     {"ms", "ms"},
      {"g", "g"},   {"dyn", "dyn"}, {"erg", "erg"}, {"n", "N"},     {"j", "J"},
      {"kg", "kg"}, {"hz", "Hz"},   {"pa", "Pa"},   {"rad", "rad"}, {"deg", "deg"}};
  std::string name = column, unit;
  const size_t us = column.rfind('_');
  if (us != std::string::npos && us + 1 < column.size()) {
    const auto it = units.find(column.substr(us + 1));
    if (it != units.end()) {
      unit = it->second;
      name = column.substr(0, us);
    }
  }
  for (char& c : name)
    if (c == '_') c = ' ';
  return unit.empty() ? name : name + " (" + unit + ")";
}

std::string find_gnuplot() {
  return find_executable("gnuplot");
}

const std::vector<std::string>& log_columns() {
  static const std::vector<std::string> cols = {
      "time_s",        "kinetic_energy",       "potential_energy", "max_violation",
      "contact_pairs", "min_contact_distance", "wall_s_per_step"};
  return cols;
}

std::vector<std::string> plot_log(const std::string& dir) {
  const std::string csv = (fs::path(dir) / "log.csv").string();
  const CsvTable t = read_csv(csv);
  // reorder to the log's standard column order
  CsvTable data;
  data.columns = log_columns();
  std::vector<int> idx;
  for (const auto& c : log_columns()) idx.push_back(t.column(c, csv));
  for (const auto& r : t.rows) {
    std::vector<double> row;
    for (int i : idx) row.push_back(r[i]);
    data.rows.push_back(std::move(row));
  }
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty())
    throw std::runtime_error("plot: gnuplot is not on PATH (install the gnuplot-nox package)");
  TempDir tmp(dir);
  const std::string dat = (tmp.path / "log.dat").string();
  write_data(data, dat);
  const std::string d = quoted(dat);
  const std::string x = "set xlabel 'time (s)'\n";
  std::vector<std::string> written;
  auto out = [&](const char* name) { return (fs::path(dir) / name).string(); };

  // the total is not conserved in general: say why it moves
  render_plot(gnuplot, tmp, out("energy.png"), "Energy",
              x +
                  "set ylabel 'energy (erg)'\n"
                  "set label 1 'total = kinetic + potential: damping takes energy out, moving "
                  "pins, clamps and objects put it in or take it out' at graph 0.01, graph 1.03 "
                  "font ',9' noenhanced\n"
                  "plot " +
                  d +
                  " u 1:2 w l ls 1 t 'kinetic', '' u 1:3 w l ls 2 t 'potential', "
                  "'' u 1:($2+$3) w l ls 5 dt 2 t 'total'\n");
  written.push_back(out("energy.png"));

  std::string viol = x + "set ylabel 'max constraint violation |C|'\n";
  if (all_positive(data, 3)) viol += "set logscale y\nset format y '10^{%L}'\n";
  render_plot(gnuplot, tmp, out("constraints.png"), "Constraints",
              viol + "plot " + d + " u 1:4 w l ls 2 t 'max |C|'\n");
  written.push_back(out("constraints.png"));

  bool touching = false;
  for (const auto& r : data.rows) touching |= r[5] >= 0;
  const std::string closest =
      touching ? ", '' u 1:($6 >= 0 ? $6 : 1/0) w l ls 2 t 'closest approach d (none: no "
                 "contact)' axes x1y2\n"
               : "\n";
  render_plot(
      gnuplot, tmp, out("contact.png"), "Contact",
      x +
          (touching ? ""
                    : "set label 2 'no yarn touches another' at graph 0.5, graph 0.5 center\n") +
          "set ylabel 'contact pairs'\n"
          "set y2label 'closest approach d = distance / 2r' noenhanced\n"
          "set ytics nomirror\nset y2tics\n"
          // d is −1 in the log where no yarn touches another: not a distance
          "plot " +
          d + " u 1:5 w l ls 1 t 'contact pairs' axes x1y1" + closest);
  written.push_back(out("contact.png"));

  render_plot(gnuplot, tmp, out("timing.png"), "Performance",
              x +
                  "set ylabel 'wall time per step (µs)'\nset yrange [0:*]\n"
                  "plot " +
                  d + " u 1:($7 * 1e6) w l ls 4 t 'wall time per step'\n");
  written.push_back(out("timing.png"));

  // forces.png: |F| of every pin, glue and clamp (columns <group>_fx, _fy, _fz)
  CsvTable forces;
  forces.columns = {"time_s"};
  std::vector<int> fx;
  for (size_t c = 0; c + 2 < t.columns.size(); ++c) {
    const std::string& name = t.columns[c];
    if (name.size() > 3 && name.compare(name.size() - 3, 3, "_fx") == 0 &&
        t.columns[c + 1] == name.substr(0, name.size() - 3) + "_fy" &&
        t.columns[c + 2] == name.substr(0, name.size() - 3) + "_fz") {
      forces.columns.push_back(name.substr(0, name.size() - 3));
      fx.push_back(static_cast<int>(c));
    }
  }
  if (!fx.empty()) {
    for (size_t r = 0; r < t.rows.size(); ++r) {
      std::vector<double> row = {data.rows[r][0]};
      for (int c : fx)
        row.push_back(std::sqrt(t.rows[r][c] * t.rows[r][c] + t.rows[r][c + 1] * t.rows[r][c + 1] +
                                t.rows[r][c + 2] * t.rows[r][c + 2]));
      forces.rows.push_back(std::move(row));
    }
    const std::string fdat = (tmp.path / "forces.dat").string();
    write_data(forces, fdat);
    std::string body = x + "set ylabel 'force (dyn)'\nset key below\nplot ";
    for (size_t g = 1; g < forces.columns.size(); ++g)
      body += (g == 1 ? quoted(fdat) : std::string(", ''")) + " u 1:" + std::to_string(g + 1) +
              " w l ls " + std::to_string((g - 1) % 6 + 1) + " t " +
              quoted("|F| " + forces.columns[g]) + " noenhanced";
    render_plot(gnuplot, tmp, out("forces.png"), "Forces of constraints and objects on the yarn",
                body + "\n");
    written.push_back(out("forces.png"));
  }
  return written;
}

std::string plot_csv(const std::string& csv, const std::string& out_png) {
  const CsvTable t = read_csv(csv);
  if (t.columns.size() < 2)
    throw std::runtime_error(csv + ": need at least two columns (x first, then y)");
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty())
    throw std::runtime_error("plot: gnuplot is not on PATH (install the gnuplot-nox package)");
  const std::string out =
      out_png.empty() ? fs::path(csv).replace_extension(".png").string() : out_png;
  check_plot_path(out);
  TempDir tmp(fs::path(csv).parent_path());
  const std::string dat = (tmp.path / "data.dat").string();
  write_data(t, dat);
  std::string body = "set xlabel " + quoted(axis_label(t.columns[0])) + " noenhanced\n";
  if (t.columns.size() == 2) {
    body += "set ylabel " + quoted(axis_label(t.columns[1])) + " noenhanced\nset key off\n";
  }
  body += "plot ";
  for (size_t c = 1; c < t.columns.size(); ++c) {
    if (c > 1) body += ", ";
    body += (c == 1 ? quoted(dat) : std::string("''")) + " u 1:" + std::to_string(c + 1) +
            " w lp ls " + std::to_string((c - 1) % 6 + 1) + " pt 7 ps 0.5 t " +
            quoted(axis_label(t.columns[c])) + " noenhanced";
  }
  body += "\n";
  render_plot(gnuplot, tmp, out, fs::path(csv).stem().string(), body);
  return out;
}

std::string plot_series(const std::vector<PlotSeries>& series, const std::string& xlabel,
                        const std::string& ylabel, const std::string& title,
                        const std::string& out_png) {
  if (series.empty()) throw std::invalid_argument("plot: no curves to draw");
  check_plot_path(out_png);
  const std::string gnuplot = find_gnuplot();
  if (gnuplot.empty())
    throw std::runtime_error("plot: gnuplot is not on PATH (install the gnuplot-nox package)");
  const fs::path out(out_png);
  TempDir tmp(out.has_parent_path() ? out.parent_path() : fs::path("."));
  std::string body = "set xlabel " + quoted(xlabel) + " noenhanced\nset ylabel " + quoted(ylabel) +
                     " noenhanced\nset key below\nplot ";
  for (size_t k = 0; k < series.size(); ++k) {
    CsvTable t;
    t.columns = {"x", "y"};
    for (size_t i = 0; i < series[k].x.size() && i < series[k].y.size(); ++i)
      t.rows.push_back({series[k].x[i], series[k].y[i]});
    const std::string dat = (tmp.path / ("series" + std::to_string(k) + ".dat")).string();
    write_data(t, dat);
    if (k > 0) body += ", ";
    body += quoted(dat) + " u 1:2 w l ls " + std::to_string(k % 6 + 1) + " t " +
            quoted(series[k].label) + " noenhanced";
  }
  render_plot(gnuplot, tmp, out_png, title, body + "\n");
  return out_png;
}

}  // namespace knit
