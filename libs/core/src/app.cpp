#include "geohaz/core/app.hpp"

#include <omp.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <new>
#include <set>
#include <system_error>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"

namespace po = boost::program_options;

namespace geohaz {

void add_common_options(po::options_description& desc, CommonOptions& o, const std::string& default_out,
                        const std::string& out_help) {
  const std::string out_text =
      !out_help.empty() ? out_help
                        : "output directory: new, empty, or holding an earlier run of this app (its files, listed in "
                          "geohaz-manifest.txt, are removed first); any other file there stops the run (exit 2)";
  // One option a line reads better than clang-format's chained layout.
  // clang-format off
  desc.add_options()
    ("help,h", "print this help and exit")
    ("version", "print the version and exit")
    ("config,c", po::value<std::string>(&o.config), "scenario configuration file (TOML)")
    ("set", po::value<std::vector<std::string>>(&o.set)->composing(),
     "override a config key (repeatable; values in SI units, TOML syntax; a key in the i-th entry of an "
     "array of tables as table[i].key, counted from 0); see the example above")
    ("out,o", po::value<std::string>(&o.out)->default_value(default_out), out_text.c_str())
    ("threads,j", po::value<int>(&o.threads)->default_value(0), "OpenMP threads (0: all cores)")
    ("quiet,q", po::bool_switch(&o.quiet), "no progress output")
    ("help-config", po::bool_switch(&o.help_config), "print every config key with unit, default and range, and exit");
  // clang-format on
}

bool parse_command_line(int argc, const char* const* argv, const std::string& app, const std::string& summary,
                        po::options_description& desc, po::positional_options_description* positional,
                        const char* exit_codes) {
  po::variables_map vm;
  try {
    // Without a positional description of its own an app takes no positional argument: an empty
    // one makes Boost reject a stray word ("too many positional options") instead of ignoring it.
    const po::positional_options_description none;
    auto parser = po::command_line_parser(argc, argv).options(desc).positional(positional ? *positional : none);
    po::store(parser.run(), vm);
    if (vm.count("help")) {
      std::cout << app << " " << GEOHAZ_VERSION << ": " << summary << "\n\n" << desc << "\n" << exit_codes << "\n";
      return false;
    }
    if (vm.count("version")) {
      std::cout << app << " " << GEOHAZ_VERSION << "\n";
      return false;
    }
    po::notify(vm);
  } catch (const po::error& e) {
    throw InputError(std::string(e.what()) + " (see " + app + " --help)", "command line");
  }
  return true;
}

ConfigReader load_config(const CommonOptions& opts) {
  ConfigReader r =
      opts.config.empty() ? ConfigReader::from_string("", "<no config file>") : ConfigReader::from_file(opts.config);
  for (const auto& s : opts.set) r.apply_override(s);
  return r;
}

int setup_threads(int threads) {
  if (threads < 0)
    throw InputError("must be ≥ 0 (0 uses all cores)", "command line", "--threads", std::to_string(threads));
  // More threads than the machine has only slow a run down, and tens of thousands make the OpenMP
  // runtime crash or run out of memory while starting them (issue #12), so they are capped.
  const int hardware = std::max(1, omp_get_num_procs());
  if (threads > hardware) {
    std::cerr << "note: --threads " << threads << " is more than the " << hardware
              << " hardware threads of this machine; using " << hardware << "\n";
    threads = hardware;
  }
  if (threads > 0) omp_set_num_threads(threads);
  return omp_get_max_threads();
}

int run_main(const std::string& app, const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::cerr << app << ": input error: " << e.what() << "\n";
    return kExitInputError;
  } catch (const SimulationError& e) {
    std::cerr << app << ": simulation stopped: " << e.what() << "\n";
    return kExitFailure;
  } catch (const IoError& e) {
    std::cerr << app << ": I/O error: " << e.what() << "\n";
    return kExitIoError;
  } catch (const std::bad_alloc&) {
    // Inputs are checked against the memory they need before anything is allocated
    // (resources.hpp); this is what is left: the machine ran short while the run was under way.
    std::cerr << app << ": system error: out of memory\n";
    return kExitIoError;
  } catch (const std::filesystem::filesystem_error& e) {
    // A path the system cannot even look up is bad input, not an I/O failure (issue #29); the
    // readers name the key first (check_file_name), this catches any other path.
    if (e.code() == std::errc::filename_too_long) {
      const std::string p = e.path1().string();
      std::cerr << app << ": input error: file name too long (" << p.size()
                << " characters): " << (p.size() > 60 ? p.substr(0, 60) + "..." : p) << "\n";
      return kExitInputError;
    }
    std::cerr << app << ": system error: " << e.what() << "\n";
    return kExitIoError;
  } catch (const std::system_error& e) {
    std::cerr << app << ": system error: " << e.what() << "\n";
    return kExitIoError;
  } catch (const std::exception& e) {
    std::cerr << app << ": error: " << e.what() << "\n";
    return kExitFailure;
  }
}

namespace {
namespace fs = std::filesystem;

/// Every file below `dir` (not the folders), as paths relative to it, sorted.
std::vector<std::string> files_below(const fs::path& dir) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it)
    if (!it->is_directory()) files.push_back(fs::relative(it->path(), dir).generic_string());
  std::sort(files.begin(), files.end());
  return files;
}

struct OutputManifest {
  std::string app;
  std::set<std::string> files;
};

std::optional<OutputManifest> read_output_manifest(const fs::path& dir) {
  std::ifstream in(dir / kOutputManifest);
  if (!in) return std::nullopt;
  OutputManifest m;
  std::string line;
  if (!std::getline(in, line) || line.rfind("app = ", 0) != 0) return std::nullopt;
  m.app = line.substr(6);
  while (std::getline(in, line))
    if (!line.empty()) m.files.insert(line);
  return m;
}

void clean_output_dir(const fs::path& out, const std::string& app, const std::vector<fs::path>& inputs) {
  check_file_name(out.string(), "command line", "--out");
  std::error_code ec;
  if (!fs::exists(out, ec)) return;
  if (!fs::is_directory(out, ec))
    throw InputError("output path exists and is not a directory", "command line", "--out", out.string());
  const auto files = files_below(out);
  if (files.empty()) return;
  const auto refuse = [&](const std::string& why) {
    throw InputError(why + "; choose a new or empty folder, or remove what is there", "command line", "--out",
                     out.string());
  };
  const auto m = read_output_manifest(out);
  if (!m) refuse("the folder holds files that no geohaz run wrote (e.g. " + files.front() + ")");
  if (m->app != app) refuse("the folder holds the output of " + m->app + ", not of " + app);
  for (const auto& f : files)
    if (f != kOutputManifest && !m->files.count(f))
      refuse("the folder holds " + f + ", which the earlier " + app + " run there did not write");
  const fs::path canonical_out = fs::weakly_canonical(out);
  for (const auto& in : inputs) {
    if (in.empty()) continue;
    const auto rel = fs::weakly_canonical(in).lexically_relative(canonical_out);
    if (!rel.empty() && *rel.begin() != "..")
      refuse("the input " + in.string() + " lies in it, and this run empties the folder first");
  }
  for (const auto& f : files) fs::remove(out / f);  // throws filesystem_error (exit 3) if it cannot
  // Sub-folders the earlier run made and that are empty now, deepest first.
  std::vector<fs::path> dirs;
  for (auto it = fs::recursive_directory_iterator(out); it != fs::recursive_directory_iterator(); ++it)
    if (it->is_directory()) dirs.push_back(it->path());
  std::sort(dirs.rbegin(), dirs.rend());
  for (const auto& d : dirs)
    if (fs::is_empty(d, ec)) fs::remove(d, ec);
}

void write_output_manifest(const fs::path& out, const std::string& app) {
  std::error_code ec;
  if (!fs::is_directory(out, ec)) return;
  std::string text = "app = " + app + "\n";
  for (const auto& f : files_below(out))
    if (f != kOutputManifest) text += f + "\n";
  write_text_file(out / kOutputManifest, text);
}
}  // namespace

int run_in_output_dir(const fs::path& out, const std::string& app, const std::vector<fs::path>& inputs,
                      const std::function<int()>& body) {
  clean_output_dir(out, app, inputs);
  int code = 0;
  try {
    code = body();
  } catch (...) {
    try {
      write_output_manifest(out, app);
    } catch (...) {  // the run's own error is the one to report
    }
    throw;
  }
  write_output_manifest(out, app);
  return code;
}

int run_config_app(int argc, const char* const* argv, const ConfigApp& app) {
  return run_main(app.name, [&]() -> int {
    CommonOptions opts;
    boost::program_options::options_description desc(app.options_caption);
    add_common_options(desc, opts, app.name + "-out");
    if (!parse_command_line(argc, argv, app.name, app.summary, desc)) return kExitOk;
    if (opts.help_config) {
      auto r = ConfigReader::describe();
      app.describe(r);
      std::cout << ConfigReader::format_reference(r.reference());
      return kExitOk;
    }
    if (opts.config.empty())
      throw InputError("--config FILE is required (see " + app.name + " --help)", "command line", "--config");
    setup_threads(opts.threads);
    auto reader = load_config(opts);
    try {
      return app.run(reader, opts);
    } catch (const InputError& e) {
      // A check deep in a library (a scenario builder, a terrain) knows what is wrong but not which
      // file it came from: everything app.run reads comes from the config, so name it.
      if (!e.file().empty()) throw;
      throw InputError(e.reason(), opts.config, e.key(), e.value());
    }
  });
}

}  // namespace geohaz
