// Strict reading of JSON input. Every access is tracked so that keys nobody read are reported as
// errors (pbrt's ReportUnused): a misspelled key never silently falls back to a default.
//
//   JsonReader r = JsonReader::from_file(path);
//   double fx = r.get<double>("fx");                 // required
//   int n = r.get_or<int>("count", 60);              // optional with a default
//   JsonReader views = r.child("views");             // object or array
//   r.finish();                                       // throws on unknown keys
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "core/error.h"

namespace weathergs {

using Json = nlohmann::json;

// Reads and parses a JSON file; syntax errors name the file, line and column.
Json read_json_file(const std::string& path);

class JsonReader {
 public:
  JsonReader(const Json& value, std::string file, std::string pointer = "");
  static JsonReader from_file(const std::string& path);  // keeps the parsed document alive

  const Json& value() const { return *value_; }
  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }
  std::string where(const std::string& key = "") const;  // "file:/ptr/key"

  bool has(const std::string& key) const;
  bool is_object() const { return value_->is_object(); }
  bool is_array() const { return value_->is_array(); }
  size_t size() const { return value_->size(); }

  template <typename T>
  T get(const std::string& key) const;
  template <typename T>
  T get_or(const std::string& key, const T& fallback) const {
    return has(key) && !(*value_)[key].is_null() ? get<T>(key) : (mark(key), fallback);
  }
  template <typename T>
  std::optional<T> get_optional(const std::string& key) const {
    if (!has(key) || (*value_)[key].is_null()) { mark(key); return std::nullopt; }
    return get<T>(key);
  }
  // Reads this value itself (for array elements: reader.at(i).as<double>()).
  template <typename T>
  T as() const;

  JsonReader child(const std::string& key) const;   // required object/array member
  JsonReader at(size_t index) const;                // array element
  std::vector<std::string> keys() const;            // object keys, marking none

  // Throws InputError naming every key of this object that was never read.
  void finish() const;
  // Marks a key as consumed without reading it (e.g. when it is passed through verbatim).
  void mark(const std::string& key) const { used_->insert(key); }

  [[noreturn]] void fail(const std::string& key, const std::string& expected) const;

 private:
  std::shared_ptr<Json> owned_;
  const Json* value_;
  std::string file_, pointer_;
  std::shared_ptr<std::set<std::string>> used_ = std::make_shared<std::set<std::string>>();
};

namespace detail {
std::string json_type_name(const Json& j);
}

template <typename T>
T JsonReader::as() const {
  const Json& v = *value_;
  try {
    if constexpr (std::is_same_v<T, bool>) {
      if (!v.is_boolean()) throw 0;
    } else if constexpr (std::is_integral_v<T>) {
      if (!v.is_number_integer()) throw 0;
    } else if constexpr (std::is_floating_point_v<T>) {
      if (!v.is_number()) throw 0;
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (!v.is_string()) throw 0;
    }
    return v.get<T>();
  } catch (...) {
    std::string expected = std::is_same_v<T, bool>           ? "a boolean"
                           : std::is_integral_v<T>           ? "an integer"
                           : std::is_floating_point_v<T>     ? "a number"
                           : std::is_same_v<T, std::string>  ? "a string"
                                                             : "a value of the right type";
    throw InputError(where(), "expected " + expected + ", got " + detail::json_type_name(v));
  }
}

template <typename T>
T JsonReader::get(const std::string& key) const {
  if (!value_->is_object()) throw InputError(where(), "expected an object");
  if (!has(key)) fail(key, "a required key");
  mark(key);
  return JsonReader((*value_)[key], file_, pointer_ + "/" + key).as<T>();
}

}  // namespace weathergs
