#include "geohaz/core/config.hpp"

#include <toml++/toml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

#include "geohaz/core/errors.hpp"

namespace geohaz {

bool Range::contains(double v) const noexcept {
  // No key takes an infinite or NaN value: "[0, inf)" means "no upper bound", not "inf allowed"
  // (run.end_time = inf never ended, young = inf blew up at step 1; issue #12).
  if (!std::isfinite(v)) return false;
  if (min_open ? !(v > min) : !(v >= min)) return false;
  if (max_open ? !(v < max) : !(v <= max)) return false;
  return true;
}

namespace {
std::string num(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string node_text(const toml::node& n) {
  std::ostringstream s;
  if (auto str = n.as_string()) {
    s << str->get();
  } else if (n.is_table()) {
    s << "<table>";
  } else {
    n.visit([&](auto&& v) { s << v; });
  }
  return s.str();
}

/// Split "a.b[2].c" into segments {"a", "b[2]", "c"}.
std::vector<std::string> split_path(std::string_view path) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : path) {
    if (c == '.') {
      out.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  out.push_back(cur);
  return out;
}

/// Largest array index a key may address (far beyond any config; keeps the index a small number).
constexpr long kMaxIndex = 100000;

/// Parse a segment "name[3]" into ("name", 3) or ("name", -1). InputError (key = `path`) for an
/// empty name or a malformed index ("a[]", "a[x]", "a[-1]", "a[99999999999999999999]", "a[1").
std::pair<std::string, long> parse_segment(const std::string& seg, std::string_view path) {
  const auto lb = seg.find('[');
  const bool has_bracket = lb != std::string::npos || seg.find(']') != std::string::npos;
  if (seg.empty() || lb == 0)
    throw InputError("malformed key: empty name in a dotted key (expected e.g. run.end_time or material[0].density)",
                     {}, std::string(path));
  if (!has_bracket) return {seg, -1};
  const std::string digits = lb == std::string::npos ? "" : seg.substr(lb + 1, seg.size() - lb - 2);
  const bool ok = lb != std::string::npos && seg.back() == ']' && !digits.empty() && digits.size() <= 6 &&
                  std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }) &&
                  std::stol(digits) <= kMaxIndex;
  if (!ok)
    throw InputError("malformed array index in '" + seg + "': expected name[N] with N an integer in [0, " +
                         std::to_string(kMaxIndex) + "]",
                     {}, std::string(path));
  return {seg.substr(0, lb), std::stol(digits)};
}

/// Insert (or replace) the node at a dotted path, creating tables and array-of-table elements.
/// With create_elements false (a --set override), the path must fit the file's structure: a value
/// is not replaced by a table nor a table by a value (InputError naming the key), and array
/// elements must exist.
void insert_path(toml::table& root, std::string_view path, const toml::node& value, bool create_elements) {
  const auto segs = split_path(path);
  toml::table* t = &root;
  std::string walked;  // the key so far, for messages
  for (std::size_t s = 0; s + 1 < segs.size(); ++s) {
    auto [name, index] = parse_segment(segs[s], path);
    walked += (walked.empty() ? "" : ".") + name;
    if (index < 0) {
      auto* child = t->get(name);
      if (child && !child->is_table() && !create_elements)
        throw InputError("'" + walked + "' is a value, not a table, so it has no key '" + segs[s + 1] + "'", {},
                         std::string(path));
      if (!child || !child->is_table()) {
        t->insert_or_assign(name, toml::table{});
        child = t->get(name);
      }
      t = child->as_table();
    } else {
      auto* child = t->get(name);
      if (!child || !child->is_array()) {
        if (!create_elements) throw InputError("no array of tables named '" + name + "'", {}, std::string(path));
        t->insert_or_assign(name, toml::array{});
        child = t->get(name);
      }
      auto* arr = child->as_array();
      if (static_cast<long>(arr->size()) <= index) {
        if (!create_elements)
          throw InputError("index out of range: the array has " + std::to_string(arr->size()) + " entries", {},
                           std::string(path));
        while (static_cast<long>(arr->size()) <= index) arr->push_back(toml::table{});
      }
      auto* elem = arr->get(static_cast<std::size_t>(index));
      if (!elem->is_table()) throw InputError("not a table", {}, std::string(path));
      t = elem->as_table();
      walked += "[" + std::to_string(index) + "]";
    }
  }
  const auto [last, last_index] = parse_segment(segs.back(), path);
  if (last_index >= 0)
    throw InputError("an element of an array of tables is a table: set one of its keys, e.g. " + last + "[" +
                         std::to_string(last_index) + "].<key>=value",
                     {}, std::string(path));
  if (!create_elements) {
    const auto* old = t->get(last);
    const bool old_is_table = old && (old->is_table() || (old->is_array() && old->as_array()->is_array_of_tables()));
    if (old_is_table)
      throw InputError("is a table (or array of tables) in the config: set its keys one at a time, e.g. " +
                           std::string(path) + ".<key>=value",
                       {}, std::string(path));
    if (value.is_table())
      throw InputError(
          "a table cannot be set with --set: set its keys one at a time, e.g. " + std::string(path) + ".<key>=value",
          {}, std::string(path));
  }
  value.visit([&](auto&& v) { t->insert_or_assign(last, v); });
}

std::string describe_path(std::string p) {
  // "layers[0].c" -> "layers[].c" for the reference.
  std::string out;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p[i] == '[') {
      out += "[]";
      while (i < p.size() && p[i] != ']') ++i;
    } else {
      out.push_back(p[i]);
    }
  }
  return out;
}
}  // namespace

struct ConfigReader::State {
  toml::table root;
  toml::table resolved;
  std::string source;
  std::filesystem::path base;
  bool describe = false;
  std::set<std::string> accessed;  // full paths of leaves and arrays of tables read
  std::vector<KeyReference> refs;
  std::set<std::string> ref_keys;
  /// Keys set on the command line (--set), with the label errors about them carry.
  std::map<std::string, std::string> overrides;

  /// Where the value of `full` came from: the command line when it (or a table above it) was set
  /// there, else the config file.
  const std::string& origin(const std::string& full) const {
    for (const auto& [key, label] : overrides)
      if (full == key || (full.size() > key.size() && full.compare(0, key.size(), key) == 0 &&
                          (full[key.size()] == '.' || full[key.size()] == '[')))
        return label;
    return source;
  }

  void record(const std::string& full, std::string type, const KeyDoc& doc, std::string def, std::string range) {
    const std::string k = describe_path(full);
    if (ref_keys.insert(k).second)
      refs.push_back({k, std::move(type), std::string(doc.unit), std::move(def), std::move(range),
                      std::string(doc.help), std::string(doc.label)});
  }
};

ConfigReader::ConfigReader(std::shared_ptr<State> state, std::string prefix)
    : state_(std::move(state)), prefix_(std::move(prefix)) {}
ConfigReader::ConfigReader(const ConfigReader&) = default;
ConfigReader& ConfigReader::operator=(const ConfigReader&) = default;
ConfigReader::ConfigReader(ConfigReader&&) noexcept = default;
ConfigReader& ConfigReader::operator=(ConfigReader&&) noexcept = default;
ConfigReader::~ConfigReader() = default;

ConfigReader ConfigReader::from_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError("config file not found (or not a regular file)", path.string());
  std::ifstream in(path);
  if (!in) throw InputError("config file cannot be opened", path.string());
  std::stringstream ss;
  ss << in.rdbuf();
  auto r = from_string(ss.str(), path.string());
  r.state_->base = std::filesystem::absolute(path).parent_path();
  return r;
}

ConfigReader ConfigReader::from_string(std::string_view text, std::string source) {
  auto st = std::make_shared<State>();
  st->source = source;
  st->base = std::filesystem::current_path();
  try {
    st->root = toml::parse(text, source);
  } catch (const toml::parse_error& e) {
    std::ostringstream s;
    s << "TOML syntax error at line " << e.source().begin.line << ", column " << e.source().begin.column << ": "
      << e.description();
    throw InputError(s.str(), source);
  }
  return ConfigReader(st, "");
}

ConfigReader ConfigReader::describe() {
  auto st = std::make_shared<State>();
  st->describe = true;
  return ConfigReader(st, "");
}

void ConfigReader::apply_override(std::string_view assignment, const std::string& origin) {
  const auto eq = assignment.find('=');
  auto trim = [](std::string_view s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return std::string(s);
  };
  if (eq == std::string_view::npos) throw InputError("--set expects key=value", origin, "", std::string(assignment));
  const std::string key = trim(assignment.substr(0, eq));
  const std::string value = trim(assignment.substr(eq + 1));
  if (key.empty()) throw InputError("--set expects key=value (empty key)", origin, "", std::string(assignment));
  toml::table parsed;
  try {
    parsed = toml::parse("v = " + value);
  } catch (const toml::parse_error&) {
    parsed = toml::table{};
    parsed.insert("v", value);  // a bare word: take it as a string
  }
  try {
    insert_path(state_->root, key, *parsed.get("v"), false);
  } catch (const InputError& e) {
    throw InputError(e.reason(), origin, key, value);
  }
  // Errors about this key (range, type, unknown key) then name the command line, not the file.
  state_->overrides[key] = origin;
}

namespace {
[[noreturn]] void type_error(const std::string& src, const std::string& key, const toml::node& n, const char* want) {
  throw InputError(std::string("wrong type: expected ") + want, src, key, node_text(n));
}
}  // namespace

double ConfigReader::get(std::string_view key, double def, Range range, KeyDoc doc) {
  const std::string full = full_key(key);
  state_->record(full, "number", doc, num(def), range.str());
  state_->accessed.insert(full);
  double v = def;
  if (!state_->describe) {
    auto node = state_->root.at_path(full);
    if (node) {
      if (auto d = node.value<double>(); d && (node.is_floating_point() || node.is_integer())) {
        v = *d;
      } else {
        type_error(state_->origin(full), full, *node.node(), "a number");
      }
      if (!range.contains(v))
        throw InputError(std::string(std::isfinite(v) ? "out of range" : "not a finite number") + ": allowed " +
                             range.str() + (doc.unit.empty() ? "" : " " + std::string(doc.unit)),
                         state_->origin(full), full, node_text(*node.node()));
    }
  }
  insert_path(state_->resolved, full, toml::value<double>(v), true);
  return v;
}

double ConfigReader::require(std::string_view key, Range range, KeyDoc doc) {
  const std::string full = full_key(key);
  if (state_->describe) {
    state_->record(full, "number", doc, "(required)", range.str());
    state_->accessed.insert(full);
    double placeholder = std::isfinite(range.min) ? range.min + (range.min_open ? 1.0 : 0.0) : 1.0;
    if (!range.contains(placeholder)) placeholder = std::isfinite(range.max) ? range.max : 0.0;
    return placeholder;
  }
  if (!state_->root.at_path(full))
    throw InputError("required key is missing (" + std::string(doc.help) + ", " + std::string(doc.unit) + ", range " +
                         range.str() + ")",
                     state_->source, full);
  const double v = get(key, 0.0, range, doc);
  state_->refs.back().default_value = "(required)";
  return v;
}

std::int64_t ConfigReader::get_int(std::string_view key, std::int64_t def, Range range, KeyDoc doc) {
  const std::string full = full_key(key);
  state_->record(full, "integer", doc, std::to_string(def), range.str());
  state_->accessed.insert(full);
  std::int64_t v = def;
  if (!state_->describe) {
    auto node = state_->root.at_path(full);
    if (node) {
      if (!node.is_integer()) type_error(state_->origin(full), full, *node.node(), "an integer");
      v = *node.value<std::int64_t>();
      if (!range.contains(static_cast<double>(v)))
        throw InputError("out of range: allowed " + range.str(), state_->origin(full), full, std::to_string(v));
    }
  }
  insert_path(state_->resolved, full, toml::value<std::int64_t>(v), true);
  return v;
}

bool ConfigReader::get_bool(std::string_view key, bool def, KeyDoc doc) {
  const std::string full = full_key(key);
  state_->record(full, "boolean", doc, def ? "true" : "false", "true|false");
  state_->accessed.insert(full);
  bool v = def;
  if (!state_->describe) {
    auto node = state_->root.at_path(full);
    if (node) {
      if (!node.is_boolean()) type_error(state_->origin(full), full, *node.node(), "true or false");
      v = *node.value<bool>();
    }
  }
  insert_path(state_->resolved, full, toml::value<bool>(v), true);
  return v;
}

std::string ConfigReader::get_string(std::string_view key, std::string_view def, KeyDoc doc) {
  const std::string full = full_key(key);
  state_->record(full, "string", doc, "\"" + std::string(def) + "\"", "");
  state_->accessed.insert(full);
  std::string v(def);
  if (!state_->describe) {
    auto node = state_->root.at_path(full);
    if (node) {
      if (!node.is_string()) type_error(state_->origin(full), full, *node.node(), "a string");
      v = *node.value<std::string>();
    }
  }
  insert_path(state_->resolved, full, toml::value<std::string>(v), true);
  return v;
}

std::string ConfigReader::require_string(std::string_view key, KeyDoc doc) {
  const std::string full = full_key(key);
  if (!state_->describe && !state_->root.at_path(full))
    throw InputError("required key is missing (" + std::string(doc.help) + ")", state_->source, full);
  auto v = get_string(key, "", doc);
  state_->refs.back().default_value = "(required)";
  return v;
}

std::string ConfigReader::get_choice(std::string_view key, std::string_view def,
                                     const std::vector<std::string>& choices, KeyDoc doc) {
  const std::string v = get_string(key, def, doc);
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : "|") + c;
  state_->refs.back().range = list;
  if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
    const std::string full = full_key(key);
    throw InputError("unknown choice; allowed: " + list, state_->origin(full), full, v);
  }
  return v;
}

std::vector<double> ConfigReader::get_array(std::string_view key, const std::vector<double>& def, Range range,
                                            KeyDoc doc, std::size_t expected_size) {
  const std::string full = full_key(key);
  std::string deftext = "[";
  for (std::size_t i = 0; i < def.size(); ++i) deftext += (i ? ", " : "") + num(def[i]);
  deftext += "]";
  state_->record(full, expected_size ? "array[" + std::to_string(expected_size) + "]" : "array", doc, deftext,
                 range.str());
  state_->accessed.insert(full);
  std::vector<double> v = def;
  if (!state_->describe) {
    auto node = state_->root.at_path(full);
    if (node) {
      const std::string& from = state_->origin(full);
      auto* arr = node.as_array();
      if (!arr) type_error(from, full, *node.node(), "an array of numbers");
      v.clear();
      for (auto& e : *arr) {
        auto d = e.value<double>();
        if (!d || !(e.is_floating_point() || e.is_integer())) type_error(from, full, e, "numbers in the array");
        if (!range.contains(*d))
          throw InputError(std::string(std::isfinite(*d) ? "array element out of range" : "array element not finite") +
                               ": allowed " + range.str(),
                           from, full, num(*d));
        v.push_back(*d);
      }
      if (expected_size && v.size() != expected_size)
        throw InputError("expected " + std::to_string(expected_size) + " numbers, got " + std::to_string(v.size()),
                         from, full, node_text(*node.node()));
      // An empty array is what an optional list defaults to, so it may be given explicitly (e.g.
      // --set run.velocity_png_times=[]); a list that has a non-empty default must not be emptied.
      if (v.empty() && !def.empty()) throw InputError("the array is empty", from, full);
    }
  }
  toml::array out;
  for (double d : v) out.push_back(d);
  insert_path(state_->resolved, full, out, true);
  return v;
}

std::vector<double> ConfigReader::require_array(std::string_view key, Range range, KeyDoc doc,
                                                std::size_t expected_size) {
  const std::string full = full_key(key);
  if (state_->describe) {
    return get_array(key, std::vector<double>(expected_size ? expected_size : 1, 0.0), Range{}, doc, 0);
  }
  if (!state_->root.at_path(full))
    throw InputError("required key is missing (" + std::string(doc.help) + ", " + std::string(doc.unit) + ")",
                     state_->source, full);
  auto v = get_array(key, {}, range, doc, expected_size);
  if (v.empty()) throw InputError("the array is empty", state_->origin(full), full);
  state_->refs.back().default_value = "(required)";
  return v;
}

bool ConfigReader::has(std::string_view key) const {
  const std::string full = full_key(key);
  return !state_->describe && static_cast<bool>(state_->root.at_path(full));
}

std::vector<ConfigReader> ConfigReader::tables(std::string_view key, KeyDoc doc) {
  const std::string full = full_key(key);
  state_->record(full, "array of tables", {"", doc.help, doc.label}, "[]", "");
  state_->accessed.insert(full);
  std::vector<ConfigReader> out;
  if (state_->describe) {
    out.push_back(ConfigReader(state_, full + "[0]"));
    return out;
  }
  auto node = state_->root.at_path(full);
  if (!node) return out;
  auto* arr = node.as_array();
  if (!arr || !arr->is_array_of_tables())
    type_error(state_->origin(full), full, *node.node(), "an array of tables ([[...]] blocks)");
  for (std::size_t i = 0; i < arr->size(); ++i) {
    out.push_back(ConfigReader(state_, full + "[" + std::to_string(i) + "]"));
    insert_path(state_->resolved, full + "[" + std::to_string(i) + "].__placeholder", toml::value<bool>(true), true);
    state_->resolved.at_path(full + "[" + std::to_string(i) + "]").as_table()->erase("__placeholder");
  }
  return out;
}

ConfigReader ConfigReader::section(std::string_view key) const {
  return ConfigReader(state_, full_key(key));
}

std::string ConfigReader::full_key(std::string_view key) const {
  return prefix_.empty() ? std::string(key) : prefix_ + "." + std::string(key);
}

void ConfigReader::finish() const {
  if (state_->describe) return;
  // Walk every leaf of the file; the first one nobody read is unknown.
  std::function<void(const toml::table&, const std::string&)> walk = [&](const toml::table& t, const std::string& pre) {
    for (auto&& [k, node] : t) {
      const std::string path = pre.empty() ? std::string(k.str()) : pre + "." + std::string(k.str());
      if (auto* sub = node.as_table()) {
        walk(*sub, path);
        continue;
      }
      if (auto* arr = node.as_array(); arr && arr->is_array_of_tables() && state_->accessed.count(path)) {
        for (std::size_t i = 0; i < arr->size(); ++i)
          walk(*arr->get(i)->as_table(), path + "[" + std::to_string(i) + "]");
        continue;
      }
      if (state_->accessed.count(path)) continue;
      // List the keys that do exist beside it.
      const auto dot = path.rfind('.');
      const std::string parent = dot == std::string::npos ? "" : describe_path(path.substr(0, dot));
      std::string valid;
      std::set<std::string> seen;
      for (const auto& r : state_->refs) {
        const auto rdot = r.key.rfind('.');
        const std::string rparent = rdot == std::string::npos ? "" : r.key.substr(0, rdot);
        std::string name = r.key.substr(rdot == std::string::npos ? 0 : rdot + 1);
        if (rparent == parent && seen.insert(name).second) valid += (valid.empty() ? "" : ", ") + name;
        // Also offer sub-tables of this level.
        if (rparent.size() > parent.size() && rparent.rfind(parent.empty() ? "" : parent + ".", 0) == 0) {
          std::string rest = rparent.substr(parent.empty() ? 0 : parent.size() + 1);
          rest = rest.substr(0, rest.find('.'));
          if (rest.size() > 2 && rest.substr(rest.size() - 2) == "[]") rest.resize(rest.size() - 2);
          if (seen.insert(rest).second) valid += (valid.empty() ? "" : ", ") + rest + ".*";
        }
      }
      throw InputError("unknown key" + std::string(parent.empty() ? "" : " in [" + parent + "]") +
                           "; valid keys here: " + (valid.empty() ? "(none)" : valid),
                       state_->origin(path), path);
    }
  };
  walk(state_->root, "");
}

namespace {
/// The shortest text that reads back as the same double (std::to_chars without a precision), kept a
/// TOML float: 0.15, not toml++'s 17-digit 0.14999999999999999 (issue #16).
std::string toml_float(double v) {
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  std::string s(buf, res.ptr);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // "3" → "3.0"; inf and nan stay
  return s;
}

std::string toml_key(const std::string& k) {
  const bool bare = !k.empty() && std::all_of(k.begin(), k.end(),
                                              [](unsigned char c) { return std::isalnum(c) || c == '_' || c == '-'; });
  if (bare) return k;
  std::ostringstream s;
  s << toml::value<std::string>(k);
  return s.str();
}

void write_toml_value(std::ostream& s, const toml::node& n) {
  if (auto d = n.as_floating_point()) {
    s << toml_float(d->get());
  } else if (auto a = n.as_array()) {
    s << "[";
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (i) s << ", ";
      write_toml_value(s, *a->get(i));
    }
    s << "]";
  } else {
    n.visit([&](auto&& v) {
      if constexpr (toml::is_table<decltype(v)>)
        s << "{}";  // not produced by the reader (tables are written as sections)
      else
        s << v;
    });
  }
}

bool is_array_of_tables(const toml::node& n) {
  auto a = n.as_array();
  return a && !a->empty() && a->is_array_of_tables();
}

/// Write `t` under the header path `path` (empty: the root): plain keys first, then sub-tables and
/// arrays of tables as their own sections, in toml++'s (sorted) key order.
void write_toml_table(std::ostream& s, const toml::table& t, const std::string& path, bool array_element) {
  bool plain = false;
  for (const auto& [k, v] : t)
    if (!v.is_table() && !is_array_of_tables(v)) plain = true;
  if (!path.empty() && (plain || array_element || t.empty()))
    s << (s.tellp() > 0 ? "\n" : "") << (array_element ? "[[" : "[") << path << (array_element ? "]]" : "]") << "\n";
  for (const auto& [k, v] : t) {
    if (v.is_table() || is_array_of_tables(v)) continue;
    s << toml_key(std::string(k.str())) << " = ";
    write_toml_value(s, v);
    s << "\n";
  }
  for (const auto& [k, v] : t) {
    const std::string sub = (path.empty() ? "" : path + ".") + toml_key(std::string(k.str()));
    if (auto tt = v.as_table()) {
      write_toml_table(s, *tt, sub, false);
    } else if (is_array_of_tables(v)) {
      for (const auto& e : *v.as_array()) write_toml_table(s, *e.as_table(), sub, true);
    }
  }
}
}  // namespace

std::string ConfigReader::resolved() const {
  std::ostringstream s;
  write_toml_table(s, state_->resolved, "", false);
  s << "\n";
  return s.str();
}

std::vector<KeyReference> ConfigReader::reference() const {
  return state_->refs;
}

std::string ConfigReader::format_reference(const std::vector<KeyReference>& refs) {
  std::ostringstream s;
  for (const auto& r : refs) {
    s << r.key << "  (" << r.type;
    if (!r.unit.empty()) s << ", " << r.unit;
    s << ")\n      " << r.help << "\n      default: " << r.default_value;
    if (!r.range.empty()) s << "   allowed: " << r.range;
    s << "\n";
  }
  return s.str();
}

const std::string& ConfigReader::source() const {
  return state_->source;
}
std::filesystem::path ConfigReader::base_dir() const {
  return state_->base;
}

std::string Range::str() const {
  if (std::isinf(min) && std::isinf(max)) return "any";
  return std::string(min_open ? "(" : "[") + num(min) + ", " + num(max) + (max_open || std::isinf(max) ? ")" : "]");
}

void check_file_name(const std::string& path, const std::string& source, const std::string& key) {
  std::size_t longest = 0, start = 0;
  while (start <= path.size()) {
    const std::size_t end = std::min(path.find('/', start), path.size());
    longest = std::max(longest, end - start);
    start = end + 1;
  }
  if (longest <= 255 && path.size() <= 4095) return;
  const std::string shown = path.size() > 60 ? path.substr(0, 60) + "..." : path;
  throw InputError("file name too long (" + std::to_string(path.size()) + " characters, the longest part " +
                       std::to_string(longest) + "): the system allows 255 per folder or file name and 4095 in all",
                   source, key, shown);
}

void check_input_file(const std::string& path, const std::string& source, const std::string& key) {
  check_file_name(path, source, key);
  if (path.empty() || path.rfind("/vsi", 0) == 0 || path.find("://") != std::string::npos) return;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError("no such file", path, key);
}

}  // namespace geohaz
