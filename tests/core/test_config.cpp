#include <gtest/gtest.h>
#include <omp.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <new>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/resources.hpp"

namespace geohaz {
namespace {

const char* kToml = R"(
# a slope
[material]
density = 1800.0
cohesion = 0          # integers are accepted as numbers
model = "drucker_prager"

[[layer]]
top = 1.0
c = 5e3
[[layer]]
top = 0.5
c = 1e4
)";

// Read the keys the example uses, as an app would.
void read_all(ConfigReader& r) {
  r.get("material.density", 2000.0, Range::positive(), {"kg/m^3", "density"});
  r.get("material.cohesion", 0.0, Range::non_negative(), {"Pa", "cohesion"});
  r.get_choice("material.model", "elastic", {"elastic", "drucker_prager"}, {"", "constitutive model"});
  for (auto& l : r.tables("layer", {"", "soil layers"})) {
    l.get("top", 0.0, Range{}, {"m", "top elevation"});
    l.get("c", 0.0, Range::non_negative(), {"Pa", "cohesion"});
  }
}

TEST(Config, ReadsTypedValuesAndArraysOfTables) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  EXPECT_DOUBLE_EQ(r.get("material.density", 0.0, Range::positive(), {"kg/m^3", ""}), 1800.0);
  EXPECT_DOUBLE_EQ(r.get("material.cohesion", 7.0, Range::non_negative(), {"Pa", ""}), 0.0);
  EXPECT_DOUBLE_EQ(r.get("material.friction", 30.0, Range::closed(0, 90), {"deg", ""}), 30.0);  // default
  auto layers = r.tables("layer", {"", ""});
  ASSERT_EQ(layers.size(), 2u);
  EXPECT_DOUBLE_EQ(layers[1].get("c", 0.0, Range{}, {"Pa", ""}), 1e4);
}

TEST(Config, UnknownKeyIsNamedWithTheValidOnes) {
  auto r = ConfigReader::from_string(std::string(kToml) + "\n[extra]\nfoo = 1\n", "slope.toml");
  read_all(r);
  try {
    r.finish();
    FAIL() << "unknown key accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "extra.foo");
    EXPECT_EQ(e.file(), "slope.toml");
    EXPECT_NE(std::string(e.what()).find("unknown key"), std::string::npos);
  }
  auto r2 = ConfigReader::from_string("[material]\ndensty = 1800\n", "slope.toml");
  read_all(r2);
  try {
    r2.finish();
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(e.key(), "material.densty");
    EXPECT_NE(msg.find("density"), std::string::npos) << msg;  // lists the valid keys beside it
    EXPECT_NE(msg.find("cohesion"), std::string::npos) << msg;
  }
}

TEST(Config, UnknownKeyInsideArrayOfTables) {
  auto r = ConfigReader::from_string("[[layer]]\ntop = 1\nphi = 30\n", "x.toml");
  read_all(r);
  try {
    r.finish();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "layer[0].phi");
  }
}

TEST(Config, AllKnownKeysPassFinish) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  read_all(r);
  EXPECT_NO_THROW(r.finish());
}

TEST(Config, WrongTypeNamesKeyAndValue) {
  auto r = ConfigReader::from_string("[material]\ndensity = \"heavy\"\n", "s.toml");
  try {
    r.get("material.density", 1.0, Range::positive(), {"kg/m^3", ""});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.key(), "material.density");
    EXPECT_EQ(e.value(), "heavy");
    EXPECT_NE(std::string(e.what()).find("expected a number"), std::string::npos);
  }
  auto r2 = ConfigReader::from_string("n = 2.5\n", "s.toml");
  EXPECT_THROW(r2.get_int("n", 1, Range::positive(), {"1", ""}), InputError);
}

TEST(Config, OutOfRangeNamesTheRange) {
  auto r = ConfigReader::from_string("[material]\nfriction_angle = 95\n", "s.toml");
  try {
    r.get("material.friction_angle", 30.0, Range::closed_open(0, 90), {"deg", ""});
    FAIL();
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("[0, 90)"), std::string::npos) << msg;
    EXPECT_NE(msg.find("deg"), std::string::npos) << msg;
    EXPECT_EQ(e.value(), "95");
  }
  auto r2 = ConfigReader::from_string("x = -1.0\n", "s.toml");
  EXPECT_THROW(r2.get("x", 1.0, Range::positive(), {"m", ""}), InputError);
  auto r3 = ConfigReader::from_string("x = nan\n", "s.toml");
  EXPECT_THROW(r3.get("x", 1.0, Range{}, {"m", ""}), InputError);  // NaN is never in range
}

TEST(Config, MissingRequiredKeyAndFile) {
  auto r = ConfigReader::from_string("", "s.toml");
  EXPECT_THROW(r.require("geometry.height", Range::positive(), {"m", "slope height"}), InputError);
  try {
    ConfigReader::from_file("/nonexistent/dir/slope.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "/nonexistent/dir/slope.toml");
  }
}

TEST(Config, SyntaxErrorGivesLine) {
  try {
    ConfigReader::from_string("a = 1\nb = = 2\n", "bad.toml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
}

TEST(Config, ChoiceListsTheAllowedValues) {
  auto r = ConfigReader::from_string("model = \"mohr\"\n", "s.toml");
  try {
    r.get_choice("model", "elastic", {"elastic", "drucker_prager"}, {"", ""});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("elastic|drucker_prager"), std::string::npos);
  }
}

TEST(Config, OverridesReplaceAndCreateKeys) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  r.apply_override("material.density=2100");
  r.apply_override("material.model = elastic");  // bare word → string
  r.apply_override("run.duration=2.5");          // new table
  r.apply_override("layer[1].c=3e3");            // element of an array of tables
  EXPECT_DOUBLE_EQ(r.get("material.density", 0.0, Range::positive(), {"", ""}), 2100.0);
  EXPECT_EQ(r.get_string("material.model", "", {"", ""}), "elastic");
  EXPECT_DOUBLE_EQ(r.get("run.duration", 0.0, Range::positive(), {"s", ""}), 2.5);
  EXPECT_DOUBLE_EQ(r.tables("layer", {"", ""})[1].get("c", 0.0, Range{}, {"", ""}), 3e3);
  EXPECT_THROW(r.apply_override("no_equals_sign"), InputError);
  EXPECT_THROW(r.apply_override("layer[5].c=1"), InputError);
}

TEST(Config, ResolvedConfigHoldsDefaultsAndParsesBack) {
  auto r = ConfigReader::from_string(kToml, "slope.toml");
  read_all(r);
  r.get("run.duration", 8.0, Range::positive(), {"s", ""});
  const std::string text = r.resolved();
  auto back = ConfigReader::from_string(text, "resolved.toml");
  EXPECT_DOUBLE_EQ(back.get("run.duration", 0.0, Range{}, {"", ""}), 8.0);
  EXPECT_DOUBLE_EQ(back.get("material.density", 0.0, Range{}, {"", ""}), 1800.0);
  EXPECT_EQ(back.tables("layer", {"", ""}).size(), 2u);
}

// The resolved config writes the shortest text that reads back as the same double (issue #16):
// 0.15, not 0.14999999999999999; every value, string, array and array of tables parses back exactly.
TEST(Config, ResolvedNumbersAreShortestRoundTrip) {
  auto r = ConfigReader::from_string(
      "[run]\nname = \"a \\\"quoted\\\" name\"\n[[layer]]\nc = 0.1\n[[layer]]\nc = 2e5\n", "x.toml");
  const double third = 1.0 / 3.0;
  r.get("run.i_cr", 0.15, Range{}, {"", ""});
  r.get("run.third", third, Range{}, {"", ""});
  r.get("run.big", 1e6, Range{}, {"", ""});
  r.get("run.whole", 3.0, Range{}, {"", ""});
  r.get_int("run.steps", 7, Range{}, {"", ""});
  r.get_bool("run.flag", true, {"", ""});
  r.get_string("run.name", "", {"", ""});
  r.get_array("run.times", {0.1, 0.2, 0.7}, Range{}, {"", ""});
  for (auto& t : r.tables("layer", {"", ""})) t.get("c", 0.0, Range{}, {"", ""});
  r.get("deep.er.key", 0.3, Range{}, {"", ""});
  const std::string text = r.resolved();
  EXPECT_NE(text.find("i_cr = 0.15\n"), std::string::npos) << text;
  EXPECT_NE(text.find("whole = 3.0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("times = [0.1, 0.2, 0.7]"), std::string::npos) << text;
  EXPECT_EQ(text.find("0.1499999"), std::string::npos) << text;
  EXPECT_EQ(text.find("0.7000000"), std::string::npos) << text;
  auto back = ConfigReader::from_string(text, "resolved.toml");
  EXPECT_EQ(back.get("run.i_cr", 0.0, Range{}, {"", ""}), 0.15);  // bit-exact, not DOUBLE_EQ
  EXPECT_EQ(back.get("run.third", 0.0, Range{}, {"", ""}), third);
  EXPECT_EQ(back.get("run.big", 0.0, Range{}, {"", ""}), 1e6);
  EXPECT_EQ(back.get("run.whole", 0.0, Range{}, {"", ""}), 3.0);
  EXPECT_EQ(back.get_int("run.steps", 0, Range{}, {"", ""}), 7);
  EXPECT_TRUE(back.get_bool("run.flag", false, {"", ""}));
  EXPECT_EQ(back.get_string("run.name", "", {"", ""}), "a \"quoted\" name");
  EXPECT_EQ(back.get_array("run.times", {}, Range{}, {"", ""}), (std::vector<double>{0.1, 0.2, 0.7}));
  auto layers = back.tables("layer", {"", ""});
  ASSERT_EQ(layers.size(), 2u);
  EXPECT_EQ(layers[0].get("c", 0.0, Range{}, {"", ""}), 0.1);
  EXPECT_EQ(layers[1].get("c", 0.0, Range{}, {"", ""}), 2e5);
  EXPECT_EQ(back.get("deep.er.key", 0.0, Range{}, {"", ""}), 0.3);
  EXPECT_NO_THROW(back.finish());
}

TEST(Config, DescribeModeBuildsTheReference) {
  auto d = ConfigReader::describe();
  read_all(d);
  d.require("geometry.height", Range::positive(), {"m", "slope height"});
  const auto refs = d.reference();
  ASSERT_GE(refs.size(), 6u);
  bool found_layer = false, found_height = false;
  for (const auto& k : refs) {
    if (k.key == "layer[].c") found_layer = k.unit == "Pa";
    if (k.key == "geometry.height") found_height = k.default_value == "(required)" && k.range == "(0, inf)";
  }
  EXPECT_TRUE(found_layer);
  EXPECT_TRUE(found_height);
  EXPECT_NE(ConfigReader::format_reference(refs).find("slope height"), std::string::npos);
}

TEST(App, ExitCodesFollowTheErrorKind) {
  EXPECT_EQ(run_main("t", [] { return 0; }), kExitOk);
  EXPECT_EQ(run_main("t", []() -> int { throw InputError("bad", "f.toml", "k", "v"); }), kExitInputError);
  EXPECT_EQ(run_main("t", []() -> int { throw SimulationError("NaN at particle 3"); }), kExitFailure);
  EXPECT_EQ(run_main("t", []() -> int { throw std::runtime_error("disk full"); }), kExitFailure);
}

TEST(App, CommandLineErrorsAreInputErrors) {
  boost::program_options::options_description desc;
  CommonOptions o;
  add_common_options(desc, o, "out");
  const char* argv[] = {"app", "--no-such-option"};
  EXPECT_THROW(parse_command_line(2, argv, "app", "", desc), InputError);
  const char* argv2[] = {"app", "--threads", "two"};
  EXPECT_THROW(parse_command_line(3, argv2, "app", "", desc), InputError);
  const char* argv3[] = {"app", "--set", "a.b=1", "--set", "c=2", "--quiet"};
  EXPECT_TRUE(parse_command_line(6, argv3, "app", "", desc));
  EXPECT_EQ(o.set.size(), 2u);
  EXPECT_TRUE(o.quiet);
  EXPECT_THROW(setup_threads(-1), InputError);
}

TEST(InputError, MessageCarriesContext) {
  InputError e("must be positive", "run.toml", "duration", "-3");
  EXPECT_EQ(std::string(e.what()), "run.toml: 'duration' = '-3': must be positive");
  EXPECT_EQ(e.reason(), "must be positive");
}

// ---- issue #12: what the fuzzer found in the config reader, the command line and run_main ----

/// The message of the InputError `f` throws ("" when it throws none).
template <class F>
std::string input_error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(App, IoAndSystemFailuresExitWithThree) {
  EXPECT_EQ(run_main("t", []() -> int { throw IoError("No space left on device", "out/a.tif"); }), kExitIoError);
  EXPECT_EQ(run_main("t", []() -> int { throw std::bad_alloc(); }), kExitIoError);
  EXPECT_EQ(run_main("t",
                     []() -> int {
                       throw std::filesystem::filesystem_error("rename",
                                                               std::make_error_code(std::errc::no_space_on_device));
                     }),
            kExitIoError);
  EXPECT_EQ(kExitIoError, 3);
}

TEST(App, ThreadsAboveTheHardwareAreCapped) {
  // 99999 threads crashed the OpenMP runtime; 2147483647 ran it out of memory.
  const int hw = omp_get_num_procs();
  EXPECT_EQ(setup_threads(99999), hw);
  EXPECT_EQ(setup_threads(2147483647), hw);
  EXPECT_EQ(setup_threads(1), 1);
  EXPECT_THROW(setup_threads(-1), InputError);
  setup_threads(hw);
}

TEST(App, StrayPositionalArgumentIsRejected) {
  boost::program_options::options_description desc;
  CommonOptions o;
  add_common_options(desc, o, "out");
  const char* argv[] = {"app", "--config", "a.toml", "extra"};
  EXPECT_THROW(parse_command_line(4, argv, "app", "", desc), InputError);
}

TEST(Config, InfinityIsOutsideEveryRange) {
  for (const char* text : {"t = inf", "t = +inf", "t = -inf", "t = nan"}) {
    EXPECT_THROW(ConfigReader::from_string(text).get("t", 1.0, Range::positive(), {"s", ""}), InputError) << text;
    EXPECT_THROW(ConfigReader::from_string(text).get("t", 1.0, Range::non_negative(), {"s", ""}), InputError) << text;
    EXPECT_THROW(ConfigReader::from_string(text).get("t", 1.0, Range{}, {"s", ""}), InputError) << text;
  }
  const std::string msg = input_error_of([] {
    ConfigReader::from_string("[run]\nend_time = inf").get("run.end_time", 1.0, Range::positive(), {"s", ""});
  });
  EXPECT_NE(msg.find("not a finite number"), std::string::npos) << msg;
  EXPECT_THROW(ConfigReader::from_string("a = [1.0, inf]").get_array("a", {}, Range{}, {"m", ""}), InputError);
}

TEST(Config, MalformedIndexInSetIsAnInputErrorNamingTheKey) {
  // Each of these ended in "error: stol", exit 1.
  for (const char* set : {"material[abc].density=1", "material[].density=1", "material[99999999999999999999].density=1",
                          "material[-1].density=1", "material[0.density=1", "material]0[.density=1", ".density=1",
                          "material..density=1"}) {
    auto r = ConfigReader::from_string("[[material]]\ndensity = 1800.0\n", "case.toml");
    const std::string msg = input_error_of([&] { r.apply_override(set); });
    EXPECT_NE(msg.find("command line (--set)"), std::string::npos) << set << ": " << msg;
    EXPECT_EQ(msg.find("case.toml"), std::string::npos) << set << ": " << msg;
  }
  auto r = ConfigReader::from_string("[[material]]\ndensity = 1800.0\n", "case.toml");
  r.apply_override("material[0].density=2000");
  EXPECT_EQ(r.tables("material", {"", ""})[0].get("density", 1.0, Range::positive(), {"", ""}), 2000.0);
}

TEST(Config, SetErrorsNameTheCommandLine) {
  auto r = ConfigReader::from_string("[run]\nend_time = 1.0\n", "case.toml");
  r.apply_override("run.end_time=-5");
  const std::string range = input_error_of([&] { r.get("run.end_time", 1.0, Range::positive(), {"s", ""}); });
  EXPECT_NE(range.find("command line (--set)"), std::string::npos) << range;
  auto r2 = ConfigReader::from_string("[run]\nend_time = 1.0\n", "case.toml");
  r2.apply_override("run.typo=1");
  r2.get("run.end_time", 1.0, Range::positive(), {"s", ""});
  const std::string unknown = input_error_of([&] { r2.finish(); });
  EXPECT_NE(unknown.find("command line (--set)"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("run.typo"), std::string::npos) << unknown;
  // A value from the file still names the file.
  auto r3 = ConfigReader::from_string("[run]\nend_time = -1.0\n", "case.toml");
  EXPECT_NE(input_error_of([&] {
              r3.get("run.end_time", 1.0, Range::positive(), {"s", ""});
            }).find("case.toml"),
            std::string::npos);
}

TEST(Config, SetCannotReplaceATableByAValueOrAValueByATable) {
  // "--set run=5" used to drop the whole [run] table and fail later on an unrelated key.
  auto r = ConfigReader::from_string("[run]\nend_time = 1.0\nscenario = \"column\"\n", "case.toml");
  const std::string msg = input_error_of([&] { r.apply_override("run=5"); });
  EXPECT_NE(msg.find("'run'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("is a table"), std::string::npos) << msg;
  EXPECT_THROW(r.apply_override("run.end_time.x=1"), InputError);
  EXPECT_THROW(r.apply_override("run={end_time=2}"), InputError);
  auto m = ConfigReader::from_string("[[material]]\ndensity = 1.0\n");
  EXPECT_THROW(m.apply_override("material=5"), InputError);
  EXPECT_THROW(m.apply_override("material[0]=5"), InputError);
}

TEST(Config, EmptyArrayMayBeSetWhenTheDefaultIsEmpty) {
  auto r = ConfigReader::from_string("[run]\nvelocity_png_times = [0.1]\n");
  r.apply_override("run.velocity_png_times=[]");
  EXPECT_TRUE(r.get_array("run.velocity_png_times", {}, Range::non_negative(), {"s", ""}).empty());
  auto r2 = ConfigReader::from_string("a = []");
  EXPECT_THROW(r2.get_array("a", {1.0, 2.0}, Range{}, {"", ""}), InputError);  // non-empty default
  auto r3 = ConfigReader::from_string("a = []");
  EXPECT_THROW(r3.require_array("a", Range{}, {"", ""}), InputError);
}

TEST(Resources, MemoryBeyondTheMachineIsAnInputErrorNamingKeyAndEstimate) {
  EXPECT_GT(available_memory_bytes(), 0.0);
  EXPECT_NO_THROW(check_memory(1e6, "a little", "case.toml", "numerics.spacing"));
  const std::string msg =
      input_error_of([] { check_memory(1e18, "1e15 particles × 1 kB", "case.toml", "numerics.spacing", "1e-6"); });
  EXPECT_NE(msg.find("numerics.spacing"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1.0 EB"), std::string::npos) << msg;
  EXPECT_NE(msg.find("1e15 particles"), std::string::npos) << msg;
  EXPECT_THROW(check_memory(std::numeric_limits<double>::infinity(), "", "", "k"), InputError);
  EXPECT_THROW(check_memory(std::numeric_limits<double>::quiet_NaN(), "", "", "k"), InputError);
}

}  // namespace
}  // namespace geohaz
