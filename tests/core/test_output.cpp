#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "child_process.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"

namespace fs = std::filesystem;

namespace geohaz {
namespace {

fs::path temp_dir(const std::string& name) {
  auto d = fs::temp_directory_path() / ("geohaz_test_" + std::to_string(getpid()) + "_" + name);
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(AtomicTextFile, AppearsOnlyOnCommit) {
  const auto d = temp_dir("atomic");
  {
    AtomicTextFile f(d / "a.csv");
    f << "x,y\n1,2\n";
    EXPECT_FALSE(fs::exists(d / "a.csv"));
    f.commit();
  }
  EXPECT_TRUE(fs::exists(d / "a.csv"));
  EXPECT_FALSE(fs::exists(d / "a.csv.partial"));
  try {
    AtomicTextFile f(d / "b.csv");
    f << "half";
    throw std::runtime_error("failure mid-way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_FALSE(fs::exists(d / "b.csv"));
  EXPECT_FALSE(fs::exists(d / "b.csv.partial"));  // nothing half-written is left
  fs::remove_all(d);
}

// One escape for every XML and HTML writer (XDMF, QGIS styles, SVG, the report): each of the five
// special characters becomes its entity, everything else (UTF-8 included) passes unchanged.
TEST(XmlEscape, ReplacesTheFiveSpecialCharactersAndNothingElse) {
  EXPECT_EQ(xml_escape("a<b>&\"c'd"), "a&lt;b&gt;&amp;&quot;c&apos;d");
  EXPECT_EQ(xml_escape("τ_y (Pa) 5 m³/s"), "τ_y (Pa) 5 m³/s");
  EXPECT_EQ(xml_escape(""), "");
  EXPECT_EQ(xml_escape("&amp;"), "&amp;amp;");  // escaping is not idempotent: escape once, at the writer
}

TEST(OutputDir, CreatesAndRejectsFiles) {
  const auto d = temp_dir("outdir");
  EXPECT_NO_THROW(make_output_dir(d / "x" / "y"));
  EXPECT_TRUE(fs::is_directory(d / "x" / "y"));
  write_text_file(d / "file", "not a dir");
  EXPECT_THROW(make_output_dir(d / "file"), InputError);
  std::ofstream(d / "z.tif.partial") << "junk";
  remove_partial_files(d);
  EXPECT_FALSE(fs::exists(d / "z.tif.partial"));
  EXPECT_TRUE(fs::exists(d / "file"));
  fs::remove_all(d);
}

TEST(Progress, LogModePrintsPlainLinesWithRateAndEta) {
  std::FILE* f = std::tmpfile();
  ProgressReporter p("test", 10.0, false, f);
  p.set_terminal(false);
  p.set_log_interval(0.0);
  p.update(0.0, 0, 100);
  p.update(5.0, 50, 100);
  EXPECT_NE(p.last_line().find("50.0%"), std::string::npos) << p.last_line();
  EXPECT_NE(p.last_line().find("ETA"), std::string::npos);
  EXPECT_NE(p.last_line().find("step 50"), std::string::npos);
  p.finish(10.0, 100, 100);
  std::rewind(f);
  char buf[4096] = {};
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const std::string out(buf, n);
  EXPECT_EQ(out.find('\r'), std::string::npos);  // no terminal control in logs
  EXPECT_NE(out.find("done in"), std::string::npos);
}

// In a pipe or log: one line at the start and one each time the run passes another 10 % (the 60 s
// interval set out of reach here), whatever the step size; a caller's estimate of the fraction done
// (a stop criterion) counts when it is ahead of t/end_time, with its note on the line.
TEST(Progress, LogModePrintsOneLinePerTenPercent) {
  std::FILE* f = std::tmpfile();
  ProgressReporter p("test", 10.0, false, f);
  p.set_terminal(false);
  p.set_log_interval(1e9);
  for (int k = 0; k <= 200; ++k) p.update(0.05 * k, k, 10);
  std::rewind(f);
  char buf[16384] = {};
  const std::size_t n = std::fread(buf, 1, sizeof buf - 1, f);
  std::fclose(f);
  const std::string out(buf, n);
  std::size_t lines = 0;
  for (char c : out) lines += c == '\n';
  EXPECT_EQ(lines, 11u) << out;  // 0 %, 10 %, ..., 100 %
  EXPECT_NE(out.find("( 50.0%)"), std::string::npos) << out;

  std::FILE* g = std::tmpfile();
  ProgressReporter q("test", 600.0, false, g);
  q.set_terminal(false);
  q.set_log_interval(1e9);
  q.update(60.0, 100, 10, 0.5, "kinetic energy 10 % of peak, stops below 1 %");
  EXPECT_NE(q.last_line().find("( 50.0%)"), std::string::npos) << q.last_line();
  EXPECT_NE(q.last_line().find("(kinetic energy 10 % of peak, stops below 1 %)"), std::string::npos);
  q.update(66.0, 110, 10, 0.05, "kinetic energy 79 % of peak, stops below 1 %");  // time ahead: 11 %
  EXPECT_NE(q.last_line().find("( 50.0%)"), std::string::npos) << "no line before the next 10 %";
  std::fclose(g);
}

TEST(Progress, QuietPrintsNothing) {
  std::FILE* f = std::tmpfile();
  ProgressReporter p("test", 1.0, true, f);
  p.set_log_interval(0.0);
  p.update(0.5, 5, 10);
  p.finish(1.0, 10, 10);
  EXPECT_EQ(std::ftell(f), 0);
  std::fclose(f);
}

TEST(Progress, DurationFormat) {
  EXPECT_EQ(format_duration(12.34), "12.3s");
  EXPECT_EQ(format_duration(185), "3m05s");
  EXPECT_EQ(format_duration(3720), "1h02m");
  EXPECT_EQ(format_duration(-1), "--");
}

// A full disk (simulated by a 1 kB file size limit in a child process): the write fails with an
// IoError naming the file, and neither the file nor its ".partial" is left behind.
TEST(AtomicTextFile, FullDiskIsAnIoErrorAndLeavesNothing) {
  const auto d = temp_dir("full");
  testing::ChildLimits lim;
  lim.file_size = 1000;
  const auto r = testing::run_in_child(
      [&] {
        try {
          write_text_file(d / "big.csv", std::string(100000, 'x'));
        } catch (const IoError& e) {
          return e.file() == (d / "big.csv").string() ? 3 : 4;
        }
        return 0;
      },
      lim);
  ASSERT_TRUE(r.exited) << r.describe();
  EXPECT_EQ(r.code, 3);
  EXPECT_FALSE(fs::exists(d / "big.csv"));
  EXPECT_FALSE(fs::exists(d / "big.csv.partial"));
  EXPECT_THROW(AtomicTextFile(d / "no_such_dir" / "a.csv"), IoError);
}

TEST(Progress, EtaOfAVeryLongRunDoesNotOverflow) {
  // An end time of 1e30 s gave an ETA beyond INT_MAX hours (undefined behaviour, garbage text).
  EXPECT_EQ(format_duration(1e30), ">99999h");
  EXPECT_EQ(format_duration(99998.0 * 3600.0), "99998h00m");
}

}  // namespace
}  // namespace geohaz
