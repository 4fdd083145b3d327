#pragma once
/// \file law_parameters.hpp
/// The parameters a law owns (issue #30). Each law of a family held in a std::variant (the
/// runout basal friction laws, the SPH constitutive models, the DEM contact laws) declares its
/// coefficients once, beside its equations:
///
///     static constexpr std::array<ParamSpec, N> parameters{{...}};   // key, default, range, unit, meaning
///     bool set(std::size_t j, double v) noexcept;                     // parameter j lands in the struct
///
/// and may add `static L from_parameters(const ParamValues&)` (when its struct is not simply the
/// parameters, e.g. a value derived from several of them) and
/// `static std::optional<ParamProblem> check(const ParamValues&)` (rules between parameters).
/// Everything else is generic over that declaration, in LawParameters below: the config keys and
/// their --help-config text (one key per name, the laws that read it listed in its help), the
/// reading of the chosen law's values with their ranges, the refusal of a key given for a law
/// that is not chosen (exit 2 naming the key and the laws it belongs to), and the labels and
/// units of the report. Two laws that read the same key (Voellmy's and Coulomb's μ) share one
/// ParamSpec object, so the key has one default, range and unit; a static_assert checks it.

#include <algorithm>
#include <array>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"

namespace geohaz {

/// One coefficient of a law.
struct ParamSpec {
  std::string_view key;      ///< name below the family's config table ("mu" is model.mu for a friction law)
  double def;                ///< default, in `unit` (as the user writes it)
  Range range;               ///< allowed values, in `unit`
  std::string_view unit;     ///< SI unit as written in the config ("1": dimensionless)
  std::string_view meaning;  ///< one line, also the label of the parameter in reports
  std::string_view note{};   ///< what --help-config adds after the laws that read the key (typical values, ...)
  /// Non-empty: the default is the value read for this other key of the law, declared before
  /// (a residual strength defaults to the peak one); `def` is then unused.
  std::string_view default_from{};
};

constexpr bool operator==(const Range& a, const Range& b) noexcept {
  return a.min == b.min && a.max == b.max && a.min_open == b.min_open && a.max_open == b.max_open;
}
constexpr bool operator==(const ParamSpec& a, const ParamSpec& b) noexcept {
  return a.key == b.key && a.def == b.def && a.range == b.range && a.unit == b.unit && a.meaning == b.meaning &&
         a.note == b.note && a.default_from == b.default_from;
}

/// The values of a law's parameters as read (in the order of its `parameters`), with whether the
/// user gave each one (else it is the default).
struct ParamValues {
  std::span<const ParamSpec> specs;
  std::vector<double> value;
  std::vector<bool> given;
  /// The value of parameter `key` (which the law declares).
  double operator[](std::string_view key) const noexcept { return value[index(key)]; }
  bool is_given(std::string_view key) const noexcept { return given[index(key)]; }
  std::size_t index(std::string_view key) const noexcept {
    std::size_t j = 0;
    while (j + 1 < specs.size() && specs[j].key != key) ++j;
    return j;
  }
};

/// A rule between a law's parameters that the values break: the key to name (relative to the
/// family's table), the reason and the offending value.
struct ParamProblem {
  std::string key;
  std::string message;
  std::string value;
};

/// Where a family's keys are and how a law is chosen, for LawParameters::read.
struct LawKeys {
  std::string_view prefix;         ///< the keys are read below this ("model."; "" in a table's reader)
  std::string_view selector;       ///< the key that chooses the law ("model.friction")
  std::string_view how_to_choose;  ///< the hint of the message refusing another law's key
  /// Whether a key of a law that is not chosen is an error (true, every family of the libraries)
  /// or read and ignored (false).
  bool refuse_other_laws_keys = true;
  std::string_view shown_prefix{};  ///< how messages name the keys, when not `prefix` ("material.")
};

/// Index of `key` in a law's parameters, -1 when the law has none of that name.
template <class L>
constexpr int parameter_index(std::string_view key) noexcept {
  for (std::size_t j = 0; j < L::parameters.size(); ++j)
    if (L::parameters[j].key == key) return static_cast<int>(j);
  return -1;
}

/// Everything generic over the declarations of a family of laws (std::variant<L...>).
template <class V>
struct LawParameters;

template <class... L>
struct LawParameters<std::variant<L...>> {
  using Variant = std::variant<L...>;

  /// A key of the family and the laws (config names, variant order) that read it.
  struct Key {
    ParamSpec spec;
    std::vector<std::string_view> laws;
  };

  /// Whether every key declared by several laws is declared identically (compile-time check).
  static constexpr bool consistent() noexcept {
    bool ok = true;
    const auto against = [&](const ParamSpec& s) {
      const auto one = [&]<class M>(std::type_identity<M>) {
        for (const ParamSpec& t : M::parameters)
          if (t.key == s.key && !(t == s)) ok = false;
      };
      (one(std::type_identity<L>{}), ...);
    };
    const auto each = [&]<class M>(std::type_identity<M>) {
      for (const ParamSpec& s : M::parameters) against(s);
    };
    (each(std::type_identity<L>{}), ...);
    return ok;
  }

  /// Every key of the family once, in order of first appearance over the laws in variant order.
  static std::vector<Key> keys() {
    std::vector<Key> out;
    const auto add = [&]<class M>(std::type_identity<M>) {
      for (const ParamSpec& s : M::parameters) {
        auto k = std::find_if(out.begin(), out.end(), [&](const Key& e) { return e.spec.key == s.key; });
        if (k == out.end()) k = out.insert(out.end(), Key{s, {}});
        k->laws.push_back(M::name);
      }
    };
    (add(std::type_identity<L>{}), ...);
    return out;
  }

  /// The --help-config text of a key: "<meaning> (<laws>[; <note>])".
  static std::string help(const Key& k) {
    std::string h(k.spec.meaning);
    h += " (";
    for (std::size_t i = 0; i < k.laws.size(); ++i) (h += i ? ", " : "") += k.laws[i];
    if (!k.spec.note.empty()) (h += "; ") += k.spec.note;
    return h + ")";
  }

  /// The parameters of the law named `law` (empty for an unknown name).
  static std::span<const ParamSpec> parameters_of(std::string_view law) noexcept {
    std::span<const ParamSpec> out;
    (void)((law == L::name ? (out = std::span<const ParamSpec>(L::parameters), true) : false) || ...);
    return out;
  }

  /// Check the values of the law named `law` against its own rules (its `check`, if any): a
  /// broken rule is an InputError naming `where` and `shown_prefix` + the key.
  static void check(std::string_view law, const ParamValues& v, const std::string& where,
                    std::string_view shown_prefix) {
    const auto one = [&]<class M>(std::type_identity<M>) {
      if constexpr (requires { M::check(v); }) {
        if (law != M::name) return;
        if (const std::optional<ParamProblem> p = M::check(v))
          throw InputError(p->message, where, std::string(shown_prefix) + p->key, p->value);
      }
    };
    (one(std::type_identity<L>{}), ...);
  }

  /// The law named `law` (a valid name) from its values, checked by its own rules first.
  static Variant make(std::string_view law, const ParamValues& v, const std::string& where,
                      std::string_view shown_prefix) {
    check(law, v, where, shown_prefix);
    std::optional<Variant> out;
    (void)((law == L::name ? (out = build<L>(v), true) : false) || ...);
    return *out;
  }

  /// The values of every key of the family as read (aligned with keys()), and whether each was given.
  struct AllValues {
    std::vector<Key> keys;
    std::vector<double> value;
    std::vector<bool> given;
  };

  /// Read every key of the family below k.prefix (so --help-config and the resolved configuration
  /// list them all, with their defaults). A key given for a law other than `law` is an InputError
  /// naming it, the laws it belongs to, k.selector and the keys `law` reads, unless
  /// k.refuse_other_laws_keys is false.
  static AllValues read_all(ConfigReader& cfg, const LawKeys& k, std::string_view law) {
    const std::string where = cfg.source().empty() ? "command line" : cfg.source();
    const std::string shown(k.shown_prefix.empty() ? k.prefix : k.shown_prefix);
    AllValues a{keys(), {}, {}};
    for (const Key& e : a.keys) {
      const ParamSpec& s = e.spec;
      const double def = s.default_from.empty() ? s.def : a.value[index(a.keys, s.default_from)];
      const std::string key = std::string(k.prefix) + std::string(s.key);
      a.value.push_back(cfg.get(key, def, s.range, {s.unit, help(e)}));
      a.given.push_back(cfg.has(key));
    }
    // A coefficient the chosen law does not use is a mistake, not something to ignore silently.
    for (std::size_t i = 0; i < a.keys.size() && k.refuse_other_laws_keys; ++i) {
      const Key& e = a.keys[i];
      if (!a.given[i] || std::find(e.laws.begin(), e.laws.end(), law) != e.laws.end()) continue;
      std::string names, accepted;
      for (std::string_view l : e.laws) (names += names.empty() ? "" : " or ") += l;
      for (const ParamSpec& s : parameters_of(law)) ((accepted += accepted.empty() ? "" : ", ") += shown) += s.key;
      const std::string key = shown + std::string(e.spec.key);
      throw InputError(key + " is given but " + std::string(k.selector) + " = " + std::string(law) +
                           " does not use it (it belongs to " + names + "; " + std::string(law) + " reads " +
                           (accepted.empty() ? std::string("none of these keys") : accepted) + "; " +
                           std::string(k.how_to_choose) + ")",
                       where, key);
    }
    return a;
  }

  /// The values of the law named `law` among all the family's.
  static ParamValues values_of(const AllValues& a, std::string_view law) {
    ParamValues v{parameters_of(law), {}, {}};
    for (const ParamSpec& s : v.specs) {
      v.value.push_back(a.value[index(a.keys, s.key)]);
      v.given.push_back(a.given[index(a.keys, s.key)]);
    }
    return v;
  }

  /// read_all, then the values of the law named `law`.
  static ParamValues read_values(ConfigReader& cfg, const LawKeys& k, std::string_view law) {
    return values_of(read_all(cfg, k, law), law);
  }

  /// read_values, then the law named `law` from them (make).
  static Variant read(ConfigReader& cfg, const LawKeys& k, std::string_view law) {
    const std::string where = cfg.source().empty() ? "command line" : cfg.source();
    return make(law, read_values(cfg, k, law), where, k.shown_prefix.empty() ? k.prefix : k.shown_prefix);
  }

 private:
  static std::size_t index(const std::vector<Key>& keys, std::string_view key) noexcept {
    return static_cast<std::size_t>(
        std::find_if(keys.begin(), keys.end(), [&](const Key& e) { return e.spec.key == key; }) - keys.begin());
  }
  template <class M>
  static M build(const ParamValues& v) {
    if constexpr (requires { M::from_parameters(v); }) {
      return M::from_parameters(v);
    } else {
      M m{};
      for (std::size_t j = 0; j < v.value.size(); ++j) m.set(j, v.value[j]);
      return m;
    }
  }
};

}  // namespace geohaz
