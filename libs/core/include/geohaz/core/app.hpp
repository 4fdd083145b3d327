#pragma once
/// \file app.hpp
/// What every geohaz command-line app shares: the common options (Boost.Program_options), the
/// exception → exit-code mapping (0 done, 1 simulation failed, 2 bad input, 3 I/O or system
/// failure; see errors.hpp), thread setup and the `--help-config` key reference.

#include <boost/program_options.hpp>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"

namespace geohaz {

/// Options every app takes.
struct CommonOptions {
  std::string config;            ///< --config FILE ("" if none)
  std::vector<std::string> set;  ///< --set key=value ...
  std::string out;               ///< --out DIR
  int threads = 0;               ///< --threads N (0: all cores)
  bool quiet = false;            ///< --quiet
  bool help_config = false;      ///< --help-config
};

/// Add --config, --set, --out, --threads, --quiet, --help, --version, --help-config.
/// `out_help` replaces the text of --out (an app whose folder policy differs: geohaz-ensemble resumes).
void add_common_options(boost::program_options::options_description& desc, CommonOptions& opts,
                        const std::string& default_out, const std::string& out_help = "");

/// Parse argv. Returns false (after printing) when --help or --version was asked for; --help ends
/// with the exit codes (`exit_codes`: a tool that runs no simulation lists its own). Unknown options, bad values, or a
/// positional argument the app does not take (`positional` null) → InputError.
bool parse_command_line(int argc, const char* const* argv, const std::string& app, const std::string& summary,
                        boost::program_options::options_description& desc,
                        boost::program_options::positional_options_description* positional = nullptr,
                        const char* exit_codes = kExitCodesHelp);

/// Read the config file (or an empty one) and apply the --set overrides.
ConfigReader load_config(const CommonOptions& opts);

/// Set the OpenMP thread count (0 = all cores); InputError when negative; more than the hardware
/// threads are capped to them with a note on stderr. Returns the count used.
int setup_threads(int threads);

/// Run an app body, mapping exceptions to messages on stderr and exit codes:
/// InputError → 2 ("app: input error: ..."), SimulationError → 1 ("app: simulation stopped: ..."),
/// IoError → 3 ("app: I/O error: ..."), std::bad_alloc and std::system_error (file system calls)
/// → 3 ("app: system error: ..."), any other exception → 1 ("app: error: ...").
int run_main(const std::string& app, const std::function<int()>& body);

/// The file a run leaves in its --out folder listing the files it wrote there (first line
/// "app = NAME", then one path a line, relative to the folder).
inline constexpr const char* kOutputManifest = "geohaz-manifest.txt";

/// The --out policy of every app (issue #16): a run never mixes its files with an earlier run's.
///  - a folder that does not exist or is empty is used as it is;
///  - a folder holding only the files that an earlier run of the same app listed in its
///    geohaz-manifest.txt is cleaned of them first (so no stale map or snapshot survives);
///  - anything else is refused with an InputError (exit 2) naming the folder and the first file that
///    no earlier run of this app wrote (or the app whose output it is), and nothing is touched.
/// An input file (`inputs`, e.g. a restart snapshot) lying in the folder is refused too, since
/// cleaning would delete it. Call after the inputs are validated; then `body` runs, and the manifest
/// is written afterwards, also when `body` throws (the exception goes on).
int run_in_output_dir(const std::filesystem::path& out, const std::string& app,
                      const std::vector<std::filesystem::path>& inputs, const std::function<int()>& body);

/// What a config-driven app (`APP --config case.toml [--set ...] [--out DIR] ...`) tells main().
struct ConfigApp {
  std::string name;             ///< program name, also the default output directory "<name>-out"
  std::string summary;          ///< --help text: what it does and its usage line
  std::string options_caption;  ///< heading of the option list (state the units)
  /// Read every key in describe mode, for --help-config (the app's own key reader).
  std::function<void(ConfigReader&)> describe;
  /// Read the loaded config (the caller calls finish() and resolved()), check it and run; returns
  /// the exit code. Called with the overrides applied and the threads set up.
  std::function<int(ConfigReader&, const CommonOptions&)> run;
};

/// main() of a config-driven app: the common options, --help / --version / --help-config,
/// --config required, threads, config loaded, then `app.run`, all inside run_main's exit-code
/// mapping.
int run_config_app(int argc, const char* const* argv, const ConfigApp& app);

}  // namespace geohaz
