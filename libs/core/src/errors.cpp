#include "geohaz/core/errors.hpp"

namespace geohaz {
namespace {
std::string compose(const std::string& what, const std::string& file, const std::string& key,
                    const std::string& value) {
  std::string s;
  if (!file.empty()) s += file + ": ";
  if (!key.empty()) s += "'" + key + "'";
  if (!value.empty()) s += (key.empty() ? "value '" : " = '") + value + "'";
  if (!key.empty() || !value.empty()) s += ": ";
  return s + what;
}
}  // namespace

InputError::InputError(const std::string& what, std::string file, std::string key, std::string value)
    : std::runtime_error(compose(what, file, key, value)),
      reason_(what),
      file_(std::move(file)),
      key_(std::move(key)),
      value_(std::move(value)) {}

IoError::IoError(const std::string& what, std::string file)
    : std::runtime_error(file.empty() ? what : file + ": " + what), file_(std::move(file)) {}

}  // namespace geohaz
