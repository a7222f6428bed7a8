#include "options.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "knit/filters/nonrigid_damping.hpp"
#include "knit/io/export.hpp"

namespace knitsim {

namespace {

// "FLOAT", "INT", … alone in the option's column: what the value is, the value line says
// the rest
CLI::Option* described(CLI::Option* opt, const std::string& doc, const std::string& line) {
  opt->description(doc + "\n" + line);
  return opt;
}

bool parse_number(const std::string& text, double& x) {
  char* end = nullptr;
  x = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0';
}

// "1/11800": the reference step of the damping strengths
std::string reference_step_text() {
  return "1/" + std::to_string(std::lround(1.0 / knit::FILTER_REFERENCE_STEP));
}

// code points, not bytes (the texts hold ², ×, –)
size_t display_width(const std::string& s) {
  size_t n = 0;
  for (unsigned char c : s) n += (c & 0xC0) != 0x80;
  return n;
}

// `text` wrapped at word boundaries to `width` columns; its own line breaks kept
std::string wrap(const std::string& text, size_t width) {
  std::string out, line, word;
  auto flush_word = [&] {
    if (word.empty()) return;
    if (!line.empty() && display_width(line) + 1 + display_width(word) > width) {
      out += line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    word.clear();
  };
  for (char c : text) {
    if (c == ' ') {
      flush_word();
    } else if (c == '\n') {
      flush_word();
      out += line + "\n";
      line.clear();
    } else {
      word += c;
    }
  }
  flush_word();
  return out + line;
}

constexpr size_t HELP_WIDTH = 100;

class HelpFormatter : public CLI::Formatter {
 public:
  // "--fire,--no-fire", not "--fire,--no-fire{false}": a flag is off unless given
  std::string make_option_name(const CLI::Option* opt, bool positional) const override {
    std::string name = CLI::Formatter::make_option_name(opt, positional);
    for (size_t open; (open = name.find('{')) != std::string::npos;) {
      const size_t close = name.find('}', open);
      if (close == std::string::npos) break;
      name.erase(open, close - open + 1);
    }
    return name;
  }
  std::string make_option_desc(const CLI::Option* opt) const override {
    return wrap(opt->get_description(), HELP_WIDTH - get_column_width());
  }
};

}  // namespace

std::string help_footer() {
  return wrap("Units are CGS: cm, g, s, dyn, erg. Exit codes: 0 done; " +
                  std::to_string(EXIT_ERROR) +
                  " an error (an unknown option, a value outside its range, a missing or "
                  "malformed input file: refused before anything ran; or an output that could "
                  "not be written); " +
                  std::to_string(EXIT_RUN_FAILED) +
                  " the run failed (its summary says why); 128 + N interrupted by signal N "
                  "(130: Ctrl-C; the summary's resume_command goes on). docs/cli.md explains "
                  "the options and the codes.",
              HELP_WIDTH);
}

std::shared_ptr<CLI::Formatter> help_formatter() {
  return std::make_shared<HelpFormatter>();
}

const char* const SOLVER_GROUP = "Solver options (docs/cli.md#solver-options)";

Range param(const std::string& name) {
  const knit::ParamRange r = knit::param_range(name);
  return closed(r.min, r.max);
}

std::string range_text(const Range& r) {
  return (r.open_low ? "(" : "[") + knit::short_number(r.lo) + ", " + knit::short_number(r.hi) +
         "]";
}

std::string number_text(double x) {
  if (x > 0 && x < 0.5) {
    const double n = std::round(1 / x);
    const bool power_of_ten = std::abs(std::log10(n) - std::round(std::log10(n))) < 1e-12;
    if (std::abs(n * x - 1) < 1e-12 && !power_of_ten)
      return knit::short_number(x) + " (1/" + std::to_string(std::llround(n)) + ")";
  }
  return knit::short_number(x);
}

std::string value_line(const std::string& unit, const std::string& default_text,
                       const std::string& range) {
  std::string line = "unit: " + unit + "; default: " + default_text;
  if (!range.empty()) line += "; range: " + range;
  return line;
}

CLI::Validator number_in(const Range& r) {
  const std::string desc = range_text(r);
  return CLI::Validator(
      [r, desc](std::string& text) -> std::string {
        double x = 0;
        if (!parse_number(text, x)) return "'" + text + "' is not a number";
        if (!std::isfinite(x))
          return "'" + text + "' is not a finite number (expected one in " + desc + ")";
        if (x < r.lo || (r.open_low && x == r.lo) || x > r.hi)
          return knit::short_number(x) + " is outside the working range " + desc;
        return "";
      },
      "");
}

CLI::Validator integer_in(long long lo, long long hi) {
  const std::string desc = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, desc](std::string& text) -> std::string {
        char* end = nullptr;
        errno = 0;
        const long long n = std::strtoll(text.c_str(), &end, 10);
        if (end == text.c_str() || *end != '\0') return "'" + text + "' is not a whole number";
        if (errno == ERANGE || n < lo || n > hi) return text + " is outside the range " + desc;
        return "";
      },
      "");
}

CLI::Validator existing_file() {
  return CLI::Validator(CLI::ExistingFile).description("");
}

CLI::Validator existing_path() {
  return CLI::Validator(CLI::ExistingPath).description("");
}

CLI::Option* add_number(CLI::App* cmd, const std::string& names, double& value,
                        const std::string& doc, const std::string& unit, const Range& range,
                        const std::string& default_text) {
  CLI::Option* opt = cmd->add_option(names, value)->check(number_in(range))->type_name("FLOAT");
  return described(opt, doc,
                   value_line(unit, default_text.empty() ? number_text(value) : default_text,
                              range_text(range)));
}

CLI::Option* add_integer(CLI::App* cmd, const std::string& names, int& value,
                         const std::string& doc, long long lo, long long hi,
                         const std::string& unit, const std::string& default_text) {
  CLI::Option* opt = cmd->add_option(names, value)->check(integer_in(lo, hi))->type_name("INT");
  return described(
      opt, doc,
      value_line(unit, default_text.empty() ? std::to_string(value) : default_text,
                 range_text(closed(static_cast<double>(lo), static_cast<double>(hi)))));
}

CLI::Option* add_path(CLI::App* cmd, const std::string& names, std::string& value,
                      const std::string& doc, const std::string& default_text,
                      const std::string& unit) {
  return described(cmd->add_option(names, value)->type_name("PATH"), doc,
                   value_line(unit, default_text));
}

CLI::Option* add_required_path(CLI::App* cmd, const std::string& names, std::string& value,
                               const std::string& doc, const std::string& unit) {
  return add_path(cmd, names, value, doc, "none (required)", unit)->required();
}

CLI::Option* add_text(CLI::App* cmd, const std::string& names, std::string& value,
                      const std::string& doc, const std::string& unit,
                      const std::string& default_text, const std::string& range) {
  return described(cmd->add_option(names, value)->type_name("TEXT"), doc,
                   value_line(unit, default_text, range));
}

CLI::Option* add_choice(CLI::App* cmd, const std::string& names, std::string& value,
                        const std::string& doc, const std::vector<std::string>& choices,
                        const std::string& default_text) {
  std::string list;
  for (size_t k = 0; k < choices.size(); ++k)
    list += (k == 0 ? "" : k + 1 == choices.size() ? " or " : ", ") + choices[k];
  CLI::Option* opt = cmd->add_option(names, value)->type_name("NAME");
  opt->check(CLI::Validator(
      [choices, list](std::string& text) -> std::string {
        for (const std::string& c : choices)
          if (text == c) return "";
        return "expected " + list + ", got \"" + text + "\"";
      },
      ""));
  return described(opt, doc,
                   value_line("name: " + list, default_text.empty() ? value : default_text));
}

// ------------------------------------------------------------------ shared options

CLI::Option* add_out_option(CLI::App* cmd, std::string& out, const std::string& doc,
                            const std::string& default_text) {
  if (default_text.empty()) return add_required_path(cmd, "--out,-o", out, doc);
  return add_path(cmd, "--out,-o", out, doc, default_text);
}

void add_overwrite_flag(CLI::App* cmd, bool& overwrite, const std::string& doc) {
  cmd->add_flag("--overwrite", overwrite,
                doc.empty() ? "replace the files of an earlier run in the output directory" : doc);
}

void add_quiet_flag(CLI::App* cmd, bool& quiet) {
  cmd->add_flag("--quiet,-q", quiet, "no progress line");
}

void add_check_crossings_flag(CLI::App* cmd, bool& check) {
  cmd->add_flag("--check-crossings", check,
                "check every step for yarns that passed through each other (a continuous test "
                "between the states before and after it); the summary's \"crossings\" gives "
                "their count (0 expected) and the first");
}

void add_threads_option(CLI::App* cmd, int& threads) {
  add_integer(cmd, "--threads,-j", threads, "worker threads", 0, 4096, "count",
              std::to_string(threads) + (threads == 0 ? " (all cores)" : ""));
}

void add_export_option(CLI::App* cmd, std::string& format) {
  add_choice(cmd, "--export", format,
             "also export the result: usd (every state, time-sampled, as frames.usda), or the "
             "final state as final.EXT (vtp: polylines; obj-mesh, ply-mesh, glb: yarn tubes); "
             "`knitsim export` has the options",
             knit::export_formats(), "none (no export)");
}

void add_size_options(CLI::App* cmd, int& rows, int& cols, const std::string& rows_doc,
                      const std::string& cols_doc, const std::string& default_note) {
  add_integer(cmd, "--rows", rows, rows_doc, 2, 1'000'000, "count",
              std::to_string(rows) + default_note);
  add_integer(cmd, "--cols", cols, cols_doc, 2, 1'000'000, "count",
              std::to_string(cols) + default_note);
}

// the solver group: the same text in simulate, relax and stretch; docs/cli.md says more

void add_time_step_option(CLI::App* cmd, double& time_step, const std::string& default_text) {
  add_number(cmd, "--time-step", time_step, "the time step h of the yarn model", "s",
             param("time_step"), default_text)
      ->group(SOLVER_GROUP);
}

void add_integrator_option(CLI::App* cmd, std::string& integrator,
                           const std::string& default_text) {
  add_choice(cmd, "--integrator", integrator,
             "how a step integrates the forces: explicit (explicit midpoint, the reference), "
             "imex (the length energy by a linearly implicit step, which lifts the step limit "
             "its stiffness sets), imex-contact (yarn–yarn contact implicit too); "
             "docs/cli.md#solver-options",
             knit::integrator_names(), default_text)
      ->group(SOLVER_GROUP);
}

void add_refuse_crossings_option(CLI::App* cmd, bool& refuse, bool negatable) {
  cmd->add_flag(
         negatable ? "--refuse-crossings,!--no-refuse-crossings" : "--refuse-crossings", refuse,
         std::string("a step in which yarns pass through each other fails (status "
                     "\"crossed\"); with --max-step-halvings it is taken again in "
                     "halves. About half a step's cost more") +
             (negatable ? " (--no-refuse-crossings: off, where a resumed state had it)" : ""))
      ->group(SOLVER_GROUP);
}

void add_implicit_bending_option(CLI::App* cmd, bool& implicit_bending, bool negatable) {
  cmd->add_flag(negatable ? "--implicit-bending,!--no-implicit-bending" : "--implicit-bending",
                implicit_bending,
                std::string("with --integrator imex or imex-contact: the bending energy "
                            "implicit too, which lifts the step limit bending sets") +
                    (negatable ? " (--no-implicit-bending: explicit, where a resumed state had "
                                 "it)"
                               : ""))
      ->group(SOLVER_GROUP);
}

void add_contact_solve_tolerance_option(CLI::App* cmd, double& tolerance,
                                        const std::string& default_text) {
  add_number(cmd, "--contact-solve-tolerance", tolerance,
             "with --integrator imex-contact: 0 solves each step once (the coupling between "
             "segments at the step's start velocity); > 0 solves by conjugate gradients until "
             "the residual is this fraction of the right-hand side",
             "fraction", param("contact_solve_tolerance"),
             default_text.empty() ? number_text(tolerance) + " (one solve)" : default_text)
      ->group(SOLVER_GROUP);
}

void add_contact_reuse_option(CLI::App* cmd, double& reuse, const std::string& default_text) {
  add_number(cmd, "--contact-reuse", reuse,
             "with --integrator imex-contact: reuse a contact evaluation's linearisation while "
             "every control point stays within this many yarn radii of where it was made",
             "yarn radii", param("contact_reuse"),
             default_text.empty() ? number_text(reuse) + " (contact every step)" : default_text)
      ->group(SOLVER_GROUP);
}

void add_max_step_halvings_option(CLI::App* cmd, int& halvings, const std::string& default_text) {
  const Range r = param("max_step_halvings");
  add_integer(cmd, "--max-step-halvings", halvings,
              "a step that fails (torn yarn, a value not finite, the projection not converged) "
              "is taken again in two halves, up to this many times (h/2ⁿ); the summary's "
              "step_halvings counts them",
              static_cast<long long>(r.lo), static_cast<long long>(r.hi), "count",
              default_text.empty() ? std::to_string(halvings) +
                                         (halvings == 0 ? " (stop at the first failed step)" : "")
                                   : default_text)
      ->group(SOLVER_GROUP);
}

void add_end_mass_floor_option(CLI::App* cmd, double& floor) {
  add_number(cmd, "--end-mass-floor", floor,
             "each yarn end's two control points get at least this fraction of an interior "
             "one's mass (0: the row sums, 1/24 at the last point; 0.5 stops a free end "
             "jittering when nothing damps it)",
             "fraction", param("end_mass_floor"))
      ->group(SOLVER_GROUP);
}

void add_contact_points_option(CLI::App* cmd, int& points) {
  const Range r = param("contact_points");
  add_integer(cmd, "--contact-points", points, "contact quadrature points per segment",
              static_cast<long long>(r.lo), static_cast<long long>(r.hi), "count per segment")
      ->group(SOLVER_GROUP);
}

void add_damping_options(CLI::App* cmd, knit::Material& material) {
  const std::string unit = "fraction per " + reference_step_text() + " s";
  const std::string rate = " (the same per second at any --time-step)";
  add_number(cmd, "--alpha-small", material.alpha_small,
             "non-rigid damping of the small regions (each stitch): the fraction of their "
             "non-rigid velocity removed per " +
                 reference_step_text() + " s" + rate,
             unit, param("alpha_small"));
  add_number(cmd, "--alpha-large", material.alpha_large,
             "non-rigid damping of the large regions (blocks of 4×4 stitches): the fraction "
             "of their non-rigid velocity removed per " +
                 reference_step_text() + " s" + rate,
             unit, param("alpha_large"));
}

}  // namespace knitsim
