#pragma once
/// \file name_table.hpp
/// The name table of a family of laws held in a std::variant (SPH constitutive models, DEM
/// contact laws, runout basal friction laws): each alternative declares its config name `name`
/// and a sentence `summary`, and the table is built from the variant, so a law added to the
/// variant is in the config's choices, its help text and `from_name` with no other edit.
/// A law's parameters are its own declaration (law_parameters.hpp), read generically; an
/// exhaustive `std::visit(Overloaded{...})` (one case per law, no generic one) remains for code
/// that must treat each law by name, so a law without its case fails to compile.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace geohaz {

template <class V>
struct NameTable;

template <class... L>
struct NameTable<std::variant<L...>> {
  using Variant = std::variant<L...>;
  /// Config names, in the order of the variant's alternatives.
  static constexpr std::array<std::string_view, sizeof...(L)> names{std::string_view(L::name)...};
  /// One sentence per law (same order), for --help-config.
  static constexpr std::array<std::string_view, sizeof...(L)> summaries{std::string_view(L::summary)...};

  /// The law of that name with its default parameters; std::nullopt for an unknown name.
  static std::optional<Variant> from_name(std::string_view n) {
    std::optional<Variant> out;
    (void)((n == L::name ? (out = L{}, true) : false) || ...);
    return out;
  }
  /// Name of the law held.
  static std::string_view name_of(const Variant& v) noexcept { return names[v.index()]; }
  /// The names as strings (the choices of ConfigReader::get_choice).
  static std::vector<std::string> choices() { return {std::string(L::name)...}; }
  /// "<what>: a = sentence; b = sentence" for the help text of the config key.
  static std::string help(std::string_view what) {
    std::string h(what);
    h += ':';
    for (std::size_t k = 0; k < names.size(); ++k) (((h += k ? "; " : " ") += names[k]) += " = ") += summaries[k];
    return h;
  }
};

/// The cases of an exhaustive std::visit, one lambda per alternative.
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};

}  // namespace geohaz
