// Unit tests for snapshot.hpp: HDF5 round trips (values, units, times, steps, attributes), lines,
// reader errors, the XDMF companion (well-formed, every HDF reference resolvable, one time step per
// snapshot) and a writer that dies without closing its file.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/particles.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz {
namespace {

namespace fs = std::filesystem;

struct Density {
  using type = double;
  static constexpr const char* label = "density";
  static constexpr const char* unit = "kg/m^3";
};
struct Flag {
  using type = std::uint8_t;
  static constexpr const char* label = "flag";
  static constexpr const char* unit = "1";
};
struct Stress2 {
  using type = Mat<2>;
  static constexpr const char* label = "stress2";
  static constexpr const char* unit = "Pa";
};
struct Stress3 {
  using type = Mat<3>;
  static constexpr const char* label = "stress3";
  static constexpr const char* unit = "Pa";
};
struct Phase {
  using type = std::int32_t;
  static constexpr const char* label = "phase";
  static constexpr const char* unit = "1";
};

using Store = ParticleStore<Position<2>, Velocity<3>, Density, ParticleId, Flag, Stress2, Stress3, Phase>;
const std::vector<std::string> kLabels = {"position", "velocity", "density", "id",
                                          "flag",     "stress2",  "stress3", "phase"};

/// A unique scratch directory removed at the end of the test.
class TempDir {
 public:
  explicit TempDir(const std::string& tag) {
    dir_ = fs::temp_directory_path() / ("geohaz_test_" + std::to_string(::getpid()) + "_snapshot_" + tag);
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  const fs::path& path() const { return dir_; }

 private:
  fs::path dir_;
};

/// Distinct, non-symmetric values so that any mix-up of particles, components or snapshots shows.
Store make_store(std::size_t n, int snapshot) {
  Store s;
  s.resize(n);
  const double o = 100.0 * snapshot;
  for (std::size_t i = 0; i < n; ++i) {
    const double d = static_cast<double>(i);
    s.get<Position<2>>()[i] = Vec2(o + d + 0.125, -d * 1.5);
    s.get<Velocity<3>>()[i] = Vec3(o + 0.1 * d, 0.2 * d - 1.0, 1e-300 * (d + 1));
    s.get<Density>()[i] = 2000.0 + o + d / 3.0;
    s.get<ParticleId>()[i] = (std::int64_t{1} << 40) + static_cast<std::int64_t>(i) + 7 * snapshot;
    s.get<Flag>()[i] = static_cast<std::uint8_t>((i + snapshot) % 3 == 0 ? 255 : i);
    Mat2 m2;
    m2 << o + d, 1.0 + d, -2.0 - d, 4.0 * d;
    s.get<Stress2>()[i] = m2;
    Mat3 m3;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) m3(r, c) = o + 10.0 * r + c + d / 7.0;
    s.get<Stress3>()[i] = m3;
    s.get<Phase>()[i] = -static_cast<std::int32_t>(i) - snapshot;
  }
  return s;
}

/// Compare every field of the store with what the reader returns for snapshot k.
void expect_snapshot_equals(const SnapshotReader& r, std::size_t k, const Store& s) {
  s.for_each_field([&](auto tag, const auto& v) {
    using Tag = decltype(tag);
    using Tr = FieldTraits<typename Tag::type>;
    SCOPED_TRACE(std::string("field ") + Tag::label + ", snapshot " + std::to_string(k));
    ASSERT_TRUE(r.has_field(k, Tag::label));
    const FieldData d = r.read(k, Tag::label);
    EXPECT_EQ(d.unit, Tag::unit);
    EXPECT_EQ(d.rows, Tr::rows);
    EXPECT_EQ(d.cols, Tr::cols);
    ASSERT_EQ(d.count, v.size());
    ASSERT_EQ(d.values.size(), v.size() * Tr::rows * Tr::cols);
    for (std::size_t i = 0; i < v.size(); ++i) {
      if constexpr (Tr::rows * Tr::cols == 1) {
        // Exact: doubles are stored as doubles, the integers here are below 2^53.
        EXPECT_EQ(d.values[i], static_cast<double>(v[i])) << "particle " << i;
      } else {
        for (int c = 0; c < Tr::rows * Tr::cols; ++c)
          EXPECT_EQ(d.values[i * Tr::rows * Tr::cols + c], static_cast<double>(v[i].data()[c]))
              << "particle " << i << " component " << c;
      }
    }
  });
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t count_occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + what.size())) ++n;
  return n;
}

/// A minimal XML check: every tag closes in order, and the text of each HDF DataItem is collected.
struct XmlCheck {
  bool well_formed = true;
  std::string error;
  std::vector<std::string> hdf_refs;
  std::vector<std::string> time_values;
  std::string root;
};

std::string attribute_value(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const auto p = tag.find(key);
  if (p == std::string::npos) return {};
  const auto q = tag.find('"', p + key.size());
  return tag.substr(p + key.size(), q - p - key.size());
}

XmlCheck check_xml(const std::string& text) {
  XmlCheck out;
  std::vector<std::string> stack;
  std::size_t pos = 0;
  bool seen_root = false;
  auto fail = [&](const std::string& why) {
    out.well_formed = false;
    out.error = why + " at offset " + std::to_string(pos);
  };
  while (out.well_formed) {
    const std::size_t lt = text.find('<', pos);
    const std::string chars = text.substr(pos, lt == std::string::npos ? std::string::npos : lt - pos);
    if (chars.find('>') != std::string::npos) return fail("stray '>'"), out;
    if (stack.empty() && chars.find_first_not_of(" \t\r\n") != std::string::npos) return fail("text outside root"), out;
    if (!stack.empty() && stack.back() == "DataItem") out.hdf_refs.push_back(chars);
    if (lt == std::string::npos) break;
    const std::size_t gt = text.find('>', lt);
    if (gt == std::string::npos) return fail("unterminated tag"), out;
    const std::string tag = text.substr(lt, gt - lt + 1);
    pos = gt + 1;
    if (tag.rfind("<?", 0) == 0 || tag.rfind("<!", 0) == 0) {
      if (seen_root) return fail("declaration after root"), out;
      continue;
    }
    if (tag.rfind("</", 0) == 0) {
      const std::string name = tag.substr(2, tag.size() - 3);
      if (stack.empty() || stack.back() != name) return fail("unbalanced </" + name + ">"), out;
      stack.pop_back();
      continue;
    }
    const std::string name = tag.substr(1, tag.find_first_of(" />", 1) - 1);
    if (stack.empty()) {
      if (seen_root) return fail("second root element"), out;
      seen_root = true;
      out.root = name;
    }
    if (count_occurrences(tag, "\"") % 2 != 0) return fail("unbalanced quotes in " + tag), out;
    if (name == "Time") out.time_values.push_back(attribute_value(tag, "Value"));
    if (tag.size() >= 2 && tag[tag.size() - 2] == '/') continue;  // self-closing
    stack.push_back(name);
  }
  if (out.well_formed && !stack.empty()) fail("unclosed <" + stack.back() + ">");
  if (out.well_formed && !seen_root) fail("no root element");
  return out;
}

/// Every HDF reference of the .xmf names the .h5 by file name only, and its dataset exists.
void expect_xdmf_consistent(const fs::path& xmf, const SnapshotReader& r, const std::string& h5_name) {
  const std::string text = read_text(xmf);
  const XmlCheck x = check_xml(text);
  ASSERT_TRUE(x.well_formed) << x.error << "\n" << text;
  EXPECT_EQ(x.root, "Xdmf");
  ASSERT_EQ(x.time_values.size(), r.snapshot_count()) << text;
  for (std::size_t k = 0; k < r.snapshot_count(); ++k) EXPECT_EQ(std::stod(x.time_values[k]), r.time(k));
  EXPECT_EQ(count_occurrences(text, "<Topology TopologyType=\"Polyvertex\""), r.snapshot_count());
  for (const std::string& ref : x.hdf_refs) {
    const auto colon = ref.find(':');
    ASSERT_NE(colon, std::string::npos) << ref;
    EXPECT_EQ(ref.substr(0, colon), h5_name) << "reference must be relative: " << ref;
    const std::string path = ref.substr(colon + 1);
    if (path.rfind("/xdmf/vertices_", 0) == 0) continue;  // connectivity helper, checked below
    ASSERT_EQ(path.rfind("/snapshots/", 0), 0u) << ref;
    const std::string group = path.substr(11, 6);
    const std::string label = path.substr(18);
    const std::size_t k = std::stoul(group);
    ASSERT_LT(k, r.snapshot_count()) << ref;
    if (label == "lines")
      EXPECT_FALSE(r.lines(k).empty()) << ref;
    else
      EXPECT_TRUE(r.has_field(k, label)) << ref;
  }
  for (std::size_t k = 0; k < r.snapshot_count(); ++k) {
    const std::size_t n = r.read(k, "position").count;
    EXPECT_NE(text.find(":/xdmf/vertices_" + std::to_string(n) + "<"), std::string::npos) << "snapshot " << k;
  }
}

TEST(Snapshot, StoreRoundTripThreeSnapshots) {
  TempDir tmp("roundtrip");
  const fs::path h5 = tmp.path() / "run.h5";
  const std::vector<std::size_t> sizes = {5, 5, 4};  // a particle removed before the last one
  const std::vector<double> times = {0.0, 0.25, 1.0 / 3.0};
  const std::vector<std::int64_t> steps = {0, 250, 333};
  const std::string config = "[run]\nend_time = 1.0 # s\nname = \"slope \\\"A\\\" <&>\"\n";
  {
    SnapshotWriter w(h5, "sph-slope", 2, config);
    EXPECT_EQ(w.path(), h5);
    EXPECT_EQ(w.xdmf_path(), tmp.path() / "run.xmf");
    w.set_attribute("crs_wkt", "PROJCS[\"WGS 84 / UTM zone 32N\"]");
    w.set_attribute("gravity", 9.81);
    w.set_attribute("gravity", 9.80665);  // replaced, not duplicated
    for (int k = 0; k < 3; ++k) w.write(make_store(sizes[k], k), times[k], steps[k]);
    EXPECT_EQ(w.snapshot_count(), 3u);
  }
  SnapshotReader r(h5);
  ASSERT_EQ(r.snapshot_count(), 3u);
  EXPECT_EQ(r.model(), "sph-slope");
  EXPECT_EQ(r.dimension(), 2);
  EXPECT_EQ(r.attribute("version"), GEOHAZ_VERSION);
  EXPECT_EQ(r.attribute("resolved_config"), config);
  EXPECT_EQ(r.attribute("crs_wkt"), "PROJCS[\"WGS 84 / UTM zone 32N\"]");
  EXPECT_EQ(std::stod(r.attribute("gravity")), 9.80665);
  EXPECT_EQ(r.attribute("dimension"), "2");
  EXPECT_EQ(r.attribute("no_such_attribute"), "");
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(r.time(k), times[k]);
    EXPECT_EQ(r.step(k), steps[k]);
    EXPECT_EQ(r.fields(k), kLabels);  // declaration order
    EXPECT_TRUE(r.lines(k).empty());
    EXPECT_FALSE(r.has_field(k, "pressure"));
    EXPECT_FALSE(r.has_field(k, "lines"));
    expect_snapshot_equals(r, k, make_store(sizes[k], static_cast<int>(k)));
  }
  EXPECT_THROW(r.read(0, "pressure"), InputError);
  EXPECT_THROW(r.time(3), std::out_of_range);
  expect_xdmf_consistent(tmp.path() / "run.xmf", r, "run.h5");
}

TEST(Snapshot, LoadFieldRestoresStore) {
  TempDir tmp("load");
  const fs::path h5 = tmp.path() / "restart.h5";
  const Store original = make_store(6, 2);
  {
    SnapshotWriter w(h5, "debris-runout", 2, "");
    w.write(original, 12.5, 1250);
  }
  SnapshotReader r(h5);
  ASSERT_EQ(r.snapshot_count(), 1u);
  Store restored;
  restored.resize(r.read(0, "position").count);
  restored.for_each_field([&](auto tag, auto&) {
    using Tag = decltype(tag);
    load_field<Tag>(r.read(0, Tag::label), restored);
  });
  original.for_each_field([&](auto tag, const auto& v) {
    using Tag = decltype(tag);
    const auto& w = restored.get<Tag>();
    ASSERT_EQ(v.size(), w.size());
    for (std::size_t i = 0; i < v.size(); ++i) EXPECT_TRUE(v[i] == w[i]) << Tag::label << " particle " << i;
  });
  // Non-symmetric tensors must come back untransposed.
  EXPECT_EQ(restored.get<Stress2>()[3](0, 1), original.get<Stress2>()[3](0, 1));
  EXPECT_NE(restored.get<Stress2>()[3](0, 1), restored.get<Stress2>()[3](1, 0));
  Store wrong;
  wrong.resize(2);
  EXPECT_THROW(load_field<Density>(r.read(0, "density"), wrong), InputError);
}

TEST(Snapshot, LinesRoundTripAndXdmfPolyline) {
  TempDir tmp("lines");
  const fs::path h5 = tmp.path() / "dem.h5";
  const std::vector<std::uint32_t> bonds = {0, 1, 1, 2, 3, 4, 4, 0};
  ParticleStore<Position<3>, Velocity<3>, Stress3> s;
  s.resize(5);
  for (std::size_t i = 0; i < 5; ++i)
    s.get<Position<3>>()[i] = Vec3(static_cast<double>(i), 2.0 * static_cast<double>(i), -1.0);
  {
    SnapshotWriter w(h5, "dem-avalanche", 3, "");
    w.write(s, 0.0, 0, bonds);
    w.write(s, 0.5, 10);  // all bonds broken
    w.write(s, 1.0, 20, std::span<const std::uint32_t>(bonds).first(2));
  }
  SnapshotReader r(h5);
  ASSERT_EQ(r.snapshot_count(), 3u);
  EXPECT_EQ(r.dimension(), 3);
  EXPECT_EQ(r.lines(0), bonds);
  EXPECT_TRUE(r.lines(1).empty());
  EXPECT_EQ(r.lines(2), std::vector<std::uint32_t>({0, 1}));
  EXPECT_EQ(r.fields(0), std::vector<std::string>({"position", "velocity", "stress3"}));
  const std::string xmf = read_text(tmp.path() / "dem.xmf");
  EXPECT_EQ(count_occurrences(xmf, "TopologyType=\"Polyline\""), 2u);
  EXPECT_EQ(count_occurrences(xmf, "CollectionType=\"Spatial\""), 3u);
  EXPECT_NE(xmf.find("GeometryType=\"XYZ\""), std::string::npos);
  EXPECT_NE(xmf.find("Name=\"velocity\" AttributeType=\"Vector\""), std::string::npos);
  EXPECT_NE(xmf.find("Name=\"stress3\" AttributeType=\"Tensor\""), std::string::npos);
  expect_xdmf_consistent(tmp.path() / "dem.xmf", r, "dem.h5");
}

TEST(Snapshot, XdmfAttributeTypesIn2D) {
  TempDir tmp("xdmf2d");
  const fs::path h5 = tmp.path() / "a b&c.h5";  // file names are escaped in the XML
  {
    SnapshotWriter w(h5, "sph-slope", 2, "");
    w.write(make_store(3, 0), 0.0, 0);
    w.write(make_store(3, 1), 0.1, 1);
  }
  const std::string xmf = read_text(tmp.path() / "a b&c.xmf");
  EXPECT_NE(xmf.find("GeometryType=\"XY\""), std::string::npos);
  EXPECT_NE(xmf.find("Name=\"density\" AttributeType=\"Scalar\""), std::string::npos);
  EXPECT_NE(xmf.find("Name=\"velocity\" AttributeType=\"Vector\""), std::string::npos);  // Vec<3>
  EXPECT_NE(xmf.find("Name=\"stress2\" AttributeType=\"Matrix\""), std::string::npos);
  EXPECT_NE(xmf.find("Name=\"id\" AttributeType=\"Scalar\" Center=\"Node\">\n"
                     "          <DataItem Dimensions=\"3\" NumberType=\"Int\" Precision=\"8\""),
            std::string::npos)
      << xmf;
  EXPECT_NE(xmf.find("NumberType=\"UChar\" Precision=\"1\""), std::string::npos);
  EXPECT_EQ(xmf.find("Polyline"), std::string::npos);
  EXPECT_NE(xmf.find("a b&amp;c.h5:/snapshots/000001/position"), std::string::npos);
  SnapshotReader r(h5);
  expect_xdmf_consistent(tmp.path() / "a b&c.xmf", r, "a b&amp;c.h5");
}

TEST(Snapshot, TwoComponentVectorIsMatrixInXdmf) {
  TempDir tmp("vec2");
  ParticleStore<Position<2>, Velocity<2>> s;
  s.resize(2);
  {
    SnapshotWriter w(tmp.path() / "v.h5", "debris-runout", 2, "");
    w.write(s, 0.0, 0);
  }
  const std::string xmf = read_text(tmp.path() / "v.xmf");
  EXPECT_NE(xmf.find("Name=\"velocity\" AttributeType=\"Matrix\""), std::string::npos) << xmf;
  EXPECT_NE(xmf.find("<DataItem Dimensions=\"2 2\""), std::string::npos) << xmf;
}

TEST(Snapshot, ReaderRejectsMissingAndNonHdf5Files) {
  TempDir tmp("errors");
  const fs::path missing = tmp.path() / "missing.h5";
  try {
    SnapshotReader r(missing);
    FAIL() << "no exception for a missing file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), missing.string());
    EXPECT_NE(std::string(e.what()).find("missing.h5"), std::string::npos);
  }
  const fs::path text = tmp.path() / "notes.h5";
  std::ofstream(text) << "this is not HDF5\n";
  try {
    SnapshotReader r(text);
    FAIL() << "no exception for a text file";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), text.string());
    EXPECT_NE(std::string(e.what()).find("not an HDF5 file"), std::string::npos);
  }
  EXPECT_THROW(SnapshotReader r(tmp.path()), InputError);  // a directory
  // A truncated HDF5 file (header only) is not a readable snapshot file either.
  {
    SnapshotWriter w(tmp.path() / "good.h5", "sph-slope", 2, "");
    w.write(make_store(50, 0), 0.0, 0);
  }
  {
    std::string bytes = read_text(tmp.path() / "good.h5");
    std::ofstream(tmp.path() / "cut.h5", std::ios::binary) << bytes.substr(0, 600);
  }
  EXPECT_THROW(SnapshotReader r(tmp.path() / "cut.h5"), InputError);
  // A valid HDF5 file without /snapshots: rename the link in the root group's name heap (same length,
  // the writer's default file format has no checksums), leaving /snapshotz.
  {
    std::string bytes = read_text(tmp.path() / "good.h5");
    const std::string name("snapshots\0", 10);
    ASSERT_EQ(count_occurrences(bytes, name), 1u);
    bytes[bytes.find(name) + 8] = 'z';
    std::ofstream(tmp.path() / "other.h5", std::ios::binary) << bytes;
  }
  try {
    SnapshotReader r(tmp.path() / "other.h5");
    FAIL() << "no exception for an HDF5 file without /snapshots";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no /snapshots group"), std::string::npos) << e.what();
  }
}

TEST(Snapshot, WriterValidatesBeforeWriting) {
  TempDir tmp("validate");
  EXPECT_THROW(SnapshotWriter(tmp.path() / "d4.h5", "sph-slope", 4, ""), std::invalid_argument);
  EXPECT_THROW(SnapshotWriter(tmp.path() / "bad.xmf", "sph-slope", 2, ""), std::invalid_argument);
  const fs::path h5 = tmp.path() / "v.h5";
  SnapshotWriter w(h5, "sph-slope", 2, "");
  std::vector<double> pos = {0, 0, 1, 0, 2, 0};
  std::vector<double> rho = {1, 2};
  std::vector<double> pos3 = {0, 0, 0};
  const FieldView p{"position", "m", ScalarType::Float64, pos.data(), 3, 2, 1};
  const FieldView short_rho{"density", "kg/m^3", ScalarType::Float64, rho.data(), 2, 1, 1};
  const FieldView p3{"position", "m", ScalarType::Float64, pos3.data(), 1, 3, 1};
  const FieldView bad_label{"a/b", "1", ScalarType::Float64, rho.data(), 3, 1, 1};
  const std::vector<FieldView> mismatch = {p, short_rho};
  const std::vector<FieldView> no_position = {short_rho};
  const std::vector<FieldView> wrong_dim = {p3};
  const std::vector<FieldView> duplicate = {p, p};
  const std::vector<FieldView> slash = {p, bad_label};
  const std::vector<FieldView> ok = {p};
  const std::vector<std::uint32_t> bad_line = {0, 3};
  const std::vector<std::uint32_t> odd_line = {0, 1, 2};
  EXPECT_THROW(w.write(0.0, 0, mismatch), std::invalid_argument);
  EXPECT_THROW(w.write(0.0, 0, no_position), std::invalid_argument);
  EXPECT_THROW(w.write(0.0, 0, wrong_dim), std::invalid_argument);
  EXPECT_THROW(w.write(0.0, 0, duplicate), std::invalid_argument);
  EXPECT_THROW(w.write(0.0, 0, slash), std::invalid_argument);
  EXPECT_THROW(w.write(0.0, 0, ok, bad_line), std::invalid_argument);
  EXPECT_THROW(w.write(0.0, 0, ok, odd_line), std::invalid_argument);
  EXPECT_THROW(w.write(std::numeric_limits<double>::quiet_NaN(), 0, ok), std::invalid_argument);
  EXPECT_EQ(w.snapshot_count(), 0u);
  w.write(1.5, 3, ok);  // the rejected calls left nothing behind: this becomes snapshot 000000
  EXPECT_EQ(w.snapshot_count(), 1u);
  SnapshotReader r(h5);
  ASSERT_EQ(r.snapshot_count(), 1u);
  EXPECT_EQ(r.step(0), 3);
  EXPECT_EQ(r.read(0, "position").values, pos);
}

TEST(Snapshot, EmptySnapshotRoundTrips) {
  TempDir tmp("empty");
  Store s;
  {
    SnapshotWriter w(tmp.path() / "e.h5", "debris-runout", 2, "");
    w.write(s, 2.0, 7);
  }
  SnapshotReader r(tmp.path() / "e.h5");
  ASSERT_EQ(r.snapshot_count(), 1u);
  const FieldData d = r.read(0, "stress3");
  EXPECT_EQ(d.count, 0u);
  EXPECT_EQ(d.rows, 3);
  EXPECT_EQ(d.cols, 3);
  EXPECT_TRUE(d.values.empty());
}

// A run killed mid-way: the child process writes two snapshots and exits with _exit, so neither the
// writer's destructor nor HDF5's atexit handler runs and the file is never closed. Everything
// written so far must be readable, and the .xmf must describe exactly those snapshots.
TEST(Snapshot, UnclosedWriterLeavesReadableFile) {
  TempDir tmp("crash");
  const fs::path h5 = tmp.path() / "killed.h5";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    int code = 0;
    try {
      auto* w = new SnapshotWriter(h5, "sph-slope", 2, "[run]\n");  // deliberately never deleted
      w->write(make_store(8, 0), 0.0, 0);
      w->write(make_store(8, 1), 0.5, 50);
    } catch (...) {
      code = 3;
    }
    ::_exit(code);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0);

  SnapshotReader r(h5);
  ASSERT_EQ(r.snapshot_count(), 2u);
  EXPECT_EQ(r.model(), "sph-slope");
  EXPECT_EQ(r.time(1), 0.5);
  EXPECT_EQ(r.step(1), 50);
  expect_snapshot_equals(r, 0, make_store(8, 0));
  expect_snapshot_equals(r, 1, make_store(8, 1));
  expect_xdmf_consistent(tmp.path() / "killed.xmf", r, "killed.h5");
  EXPECT_FALSE(fs::exists(tmp.path() / "killed.xmf.partial"));
}

// A reader can look at the file of a run that is still writing: the writer keeps no file lock and
// has flushed every snapshot it reported written.
TEST(Snapshot, ReadableWhileWriterInAnotherProcessIsAlive) {
  TempDir tmp("live");
  const fs::path h5 = tmp.path() / "live.h5";
  int to_parent[2], to_child[2];
  ASSERT_EQ(::pipe(to_parent), 0);
  ASSERT_EQ(::pipe(to_child), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    char c = 'x';
    try {
      SnapshotWriter w(h5, "dem-avalanche", 2, "");
      w.write(make_store(4, 0), 0.0, 0);
      c = 'w';
    } catch (...) {
    }
    // Stay alive, file open, until the parent has read it.
    if (::write(to_parent[1], &c, 1) != 1 || ::read(to_child[0], &c, 1) != 1) ::_exit(4);
    ::_exit(0);
  }
  char c = 0;
  ASSERT_EQ(::read(to_parent[0], &c, 1), 1);
  ASSERT_EQ(c, 'w');
  std::size_t count = 0;
  std::vector<double> density;
  try {
    SnapshotReader r(h5);
    count = r.snapshot_count();
    if (count > 0) density = r.read(0, "density").values;
  } catch (const std::exception& e) {
    ADD_FAILURE() << e.what();
  }
  c = 'q';
  ASSERT_EQ(::write(to_child[1], &c, 1), 1);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  for (int fd : {to_parent[0], to_parent[1], to_child[0], to_child[1]}) ::close(fd);
  EXPECT_EQ(count, 1u);
  EXPECT_EQ(density, make_store(4, 0).get<Density>());
}

// A full disk mid-run (a 300 kB file size limit in a child process; each big snapshot needs about
// 1.3 MB): the writer refuses the snapshot that does not fit with an IoError before touching the
// file, so the snapshots written before stay readable, the .xmf lists exactly them, and the
// process ends normally (with HDF5 1.10 a failed flush used to crash in HDF5's atexit clean-up).
TEST(Snapshot, FullDiskKeepsTheSnapshotsSoFarReadable) {
  TempDir tmp("full");
  const fs::path h5 = tmp.path() / "full.h5";
  testing::ChildLimits lim;
  lim.file_size = 300 * 1000;
  const auto r = testing::run_in_child(
      [&] {
        SnapshotWriter w(h5, "sph-slope", 2, "[run]\n");
        w.write(make_store(8, 0), 0.0, 0);
        w.write(make_store(8, 1), 0.5, 50);
        try {
          for (int k = 2; k < 10; ++k) w.write(make_store(20000, k), k, 100 * k);
        } catch (const IoError&) {
          return 3;
        }
        return 0;
      },
      lim);
  ASSERT_TRUE(r.exited) << r.describe() << "\n" << r.err;
  ASSERT_EQ(r.code, 3) << r.err;
  SnapshotReader rd(h5);
  ASSERT_EQ(rd.snapshot_count(), 2u);
  expect_snapshot_equals(rd, 1, make_store(8, 1));
  expect_xdmf_consistent(tmp.path() / "full.xmf", rd, "full.h5");
  EXPECT_FALSE(fs::exists(tmp.path() / "full.xmf.partial"));
}

// A run whose end time falls on a snapshot time wrote its last state twice (every particle listed
// twice at that time in ParaView): the same step and time is written once.
TEST(Snapshot, SameStepAndTimeIsWrittenOnce) {
  TempDir tmp("twice");
  const fs::path h5 = tmp.path() / "twice.h5";
  {
    SnapshotWriter w(h5, "dem-avalanche", 2, "");
    w.write(make_store(4, 0), 0.0, 0);
    w.write(make_store(4, 1), 1.0, 10);
    w.write(make_store(4, 1), 1.0, 10);
    EXPECT_EQ(w.snapshot_count(), 2u);
    w.write(make_store(4, 2), 1.0, 11);  // a later step at the same time is a new state
    EXPECT_EQ(w.snapshot_count(), 3u);
  }
  SnapshotReader rd(h5);
  EXPECT_EQ(rd.snapshot_count(), 3u);
  expect_xdmf_consistent(tmp.path() / "twice.xmf", rd, "twice.h5");
}

/// Two processes (the test forks) behind core's Communicator, joined by two pipes: enough for the
/// snapshot writer of several processes, whose only collective call is all_gather.
class PipeCommunicator final : public Communicator {
 public:
  PipeCommunicator(int rank, int to_peer, int from_peer) : rank_(rank), to_(to_peer), from_(from_peer) {}
  int rank() const override { return rank_; }
  int size() const override { return 2; }
  std::vector<double> all_gather(std::span<const double> v) const override {
    const std::size_t bytes = v.size() * sizeof(double);
    if (::write(to_, v.data(), bytes) != static_cast<ssize_t>(bytes)) throw std::runtime_error("pipe write");
    std::vector<double> peer(v.size());
    std::size_t got = 0;
    while (got < bytes) {
      const ssize_t r = ::read(from_, reinterpret_cast<char*>(peer.data()) + got, bytes - got);
      if (r <= 0) throw std::runtime_error("pipe read");
      got += static_cast<std::size_t>(r);
    }
    std::vector<double> out(v.begin(), v.end());
    out.insert(rank_ == 0 ? out.end() : out.begin(), peer.begin(), peer.end());
    return out;
  }
  void max_all(std::span<double>) const override { throw std::logic_error("not used"); }
  void sum_all(std::span<std::int64_t>) const override { throw std::logic_error("not used"); }
  std::vector<std::byte> all_gather_bytes(std::span<const std::byte>) const override {
    throw std::logic_error("not used");
  }
  std::vector<std::int64_t> exchange_counts(std::span<const std::int64_t>) const override {
    throw std::logic_error("not used");
  }
  void exchange(std::span<const std::byte>, std::span<const std::int64_t>, std::span<std::byte>,
                std::span<const std::int64_t>) const override {
    throw std::logic_error("not used");
  }

 private:
  int rank_, to_, from_;
};

/// Rows [first, last) of a store.
Store rows_of(const Store& full, std::size_t first, std::size_t last) {
  Store s = full;
  std::vector<std::uint8_t> drop(full.size(), 1);
  for (std::size_t i = first; i < last; ++i) drop[i] = 0;
  s.remove_if(drop);
  return s;
}

// Issue #36: a run over two processes writes its snapshots through part files, one per process, and
// the file itself reads as one dataset per field with every particle, in rank order: here three
// snapshots of 8 particles split 5/3, 2/6 and 0/8 (a rank without particles) between the ranks.
TEST(Snapshot, TwoProcessesWriteOneFileThroughTheirPartFiles) {
  TempDir tmp("parts");
  const fs::path h5 = tmp.path() / "run.h5";
  const std::size_t split[3] = {5, 2, 0};
  int p01[2], p10[2];
  ASSERT_EQ(::pipe(p01), 0);
  ASSERT_EQ(::pipe(p10), 0);
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  const int rank = pid == 0 ? 1 : 0;
  int failed = 0;
  try {
    auto comm = rank == 0 ? std::make_shared<PipeCommunicator>(0, p01[1], p10[0])
                          : std::make_shared<PipeCommunicator>(1, p10[1], p01[0]);
    SnapshotWriter w(h5, "test", 2, "key = 1\n", comm);
    w.set_attribute("note", "rank 0's");
    for (int k = 0; k < 3; ++k) {
      const Store full = make_store(8, k);
      const Store mine = rank == 0 ? rows_of(full, 0, split[k]) : rows_of(full, split[k], 8);
      w.write(mine, 0.5 * k, 10 * k);
    }
    w.write(rows_of(make_store(8, 2), 0, rank == 0 ? 0 : 8), 1.0, 20);  // the same state again: nothing written
    EXPECT_EQ(w.snapshot_count(), 3u);
  } catch (const std::exception& e) {
    failed = 1;
    if (rank == 0) ADD_FAILURE() << e.what();
  }
  if (rank == 1) ::_exit(failed);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "the second process failed";
  ASSERT_EQ(failed, 0);

  EXPECT_TRUE(fs::exists(tmp.path() / "run.rank0000.h5"));
  EXPECT_TRUE(fs::exists(tmp.path() / "run.rank0001.h5"));
  EXPECT_FALSE(fs::exists(tmp.path() / "run.rank0001.xmf"));  // one XDMF file for the run
  {
    SnapshotReader r(h5);
    ASSERT_EQ(r.snapshot_count(), 3u);
    EXPECT_EQ(r.attribute("note"), "rank 0's");
    EXPECT_EQ(r.attribute("ranks"), "2");
    EXPECT_EQ(r.attribute("resolved_config"), "key = 1\n");
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(r.time(static_cast<std::size_t>(k)), 0.5 * k);
      EXPECT_EQ(r.step(static_cast<std::size_t>(k)), 10 * k);
      expect_snapshot_equals(r, static_cast<std::size_t>(k), make_store(8, k));
    }
    expect_xdmf_consistent(tmp.path() / "run.xmf", r, "run.h5");
    // A part file alone is a snapshot file of that rank's particles.
    SnapshotReader part(tmp.path() / "run.rank0001.h5");
    EXPECT_EQ(part.read(0, "position").count, 3u);
  }
  // From another working directory (the parts are found beside the file), and not without them.
  const fs::path cwd = fs::current_path();
  fs::current_path(fs::temp_directory_path());
  EXPECT_EQ(SnapshotReader(h5).read(1, "density").count, 8u);
  fs::current_path(cwd);
  fs::remove(tmp.path() / "run.rank0001.h5");
  EXPECT_THROW(SnapshotReader{h5}, InputError);
}

}  // namespace
}  // namespace geohaz
