#include "geohaz/core/app.hpp"

#include <omp.h>

#include <algorithm>
#include <iostream>
#include <new>
#include <system_error>

#include "geohaz/core/errors.hpp"

namespace po = boost::program_options;

namespace geohaz {

void add_common_options(po::options_description& desc, CommonOptions& o, const std::string& default_out) {
  desc.add_options()
    ("help,h", "print this help and exit")
    ("version", "print the version and exit")
    ("config,c", po::value<std::string>(&o.config), "scenario configuration file (TOML)")
    ("set", po::value<std::vector<std::string>>(&o.set)->composing(),
     "override a config key, e.g. --set material.cohesion=5e3 (repeatable; values in SI units)")
    ("out,o", po::value<std::string>(&o.out)->default_value(default_out), "output directory")
    ("threads,j", po::value<int>(&o.threads)->default_value(0), "OpenMP threads (0: all cores)")
    ("quiet,q", po::bool_switch(&o.quiet), "no progress output")
    ("help-config", po::bool_switch(&o.help_config), "print every config key with unit, default and range, and exit");
}

bool parse_command_line(int argc, const char* const* argv, const std::string& app, const std::string& summary,
                        po::options_description& desc, po::positional_options_description* positional) {
  po::variables_map vm;
  try {
    // Without a positional description of its own an app takes no positional argument: an empty
    // one makes Boost reject a stray word ("too many positional options") instead of ignoring it.
    const po::positional_options_description none;
    auto parser = po::command_line_parser(argc, argv).options(desc).positional(positional ? *positional : none);
    po::store(parser.run(), vm);
    if (vm.count("help")) {
      std::cout << app << " " << GEOHAZ_VERSION << ": " << summary << "\n\n" << desc << "\n" << kExitCodesHelp << "\n";
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
  ConfigReader r = opts.config.empty() ? ConfigReader::from_string("", "<no config file>")
                                       : ConfigReader::from_file(opts.config);
  for (const auto& s : opts.set) r.apply_override(s);
  return r;
}

int setup_threads(int threads) {
  if (threads < 0) throw InputError("must be ≥ 0 (0 uses all cores)", "command line", "--threads", std::to_string(threads));
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
  } catch (const std::system_error& e) {  // includes std::filesystem::filesystem_error
    std::cerr << app << ": system error: " << e.what() << "\n";
    return kExitIoError;
  } catch (const std::exception& e) {
    std::cerr << app << ": error: " << e.what() << "\n";
    return kExitFailure;
  }
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
