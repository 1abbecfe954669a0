// Strict reading of JSON input. Every access is tracked so that keys nobody read are reported as
// errors (pbrt's ReportUnused): a misspelled key never silently falls back to a default.
//
//   JsonReader r = JsonReader::from_file(path);
//   double fx = r.get<double>("fx");                 // required
//   int n = r.get_or<int>("count", 60);              // optional with a default
//   JsonReader views = r.child("views");             // object or array
//   double x = r.get_number_or("rate_mm_h", 25, 0, 500);           // bounded, finite
//   auto wind = r.get_array_or<3>("wind_m_s", {0, 0, 0});          // fixed-size numeric array
//   auto radius = r.get_range_or("radius_mm", {0.5, 3.0});         // x or [min, max]
//   Mode m = r.get_enum_or("mode", Mode::kA, {Mode::kA, Mode::kB}); // by to_string(Mode)
//   r.finish();                                       // throws on unknown keys
//
// Every helper words its errors the same way: "<file>:<pointer>: expected <rule>, got <value>".
#pragma once

#include <array>
#include <initializer_list>
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

// How a stage decides whether its output on disk is current: "" when `recorded` (the settings record
// the stage wrote beside its output) holds every key of `expected` with the same value, else
// "KEY: holds A, asked for B" for the first key that differs.
std::string settings_mismatch(const Json& recorded, const Json& expected);

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

  // Bounded numbers: finite and within [lo, hi] (InputError otherwise).
  double get_number(const std::string& key, double lo, double hi) const;
  double get_number_or(const std::string& key, double fallback, double lo, double hi) const;
  // Arrays of exactly N finite numbers, each within [lo, hi].
  template <size_t N>
  std::array<double, N> get_array(const std::string& key, double lo = -kHuge, double hi = kHuge) const;
  template <size_t N>
  std::array<double, N> get_array_or(const std::string& key, const std::array<double, N>& fallback,
                                     double lo = -kHuge, double hi = kHuge) const {
    return has(key) && !(*value_)[key].is_null() ? get_array<N>(key, lo, hi) : (mark(key), fallback);
  }
  // A range: a number x (meaning [x, x]) or [min, max] with min <= max, finite, within [lo, hi].
  std::array<double, 2> get_range_or(const std::string& key, const std::array<double, 2>& fallback,
                                     double lo = -kHuge, double hi = kHuge) const;
  // An enum spelled as a string: one of to_string(v) for v in `values`.
  template <typename E>
  E get_enum(const std::string& key, std::initializer_list<E> values) const {
    return get_enum(key, std::vector<E>(values));
  }
  template <typename E>
  E get_enum(const std::string& key, const std::vector<E>& values) const;
  template <typename E>
  E get_enum_or(const std::string& key, E fallback, std::initializer_list<E> values) const {
    return has(key) && !(*value_)[key].is_null() ? get_enum<E>(key, values) : (mark(key), fallback);
  }
  static constexpr double kHuge = 1.0e300;

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
std::string format_number(double v);
// The one wording of a bounded-value error: "expected <what> in [lo, hi], got v".
[[noreturn]] void out_of_bounds(const std::string& where, const std::string& what, double lo, double hi, double v);
}

template <size_t N>
std::array<double, N> JsonReader::get_array(const std::string& key, double lo, double hi) const {
  JsonReader a = child(key);
  if (!a.is_array() || a.size() != N)
    throw InputError(a.where(), "expected an array of " + std::to_string(N) + " numbers, got " +
                                    (a.is_array() ? std::to_string(a.size()) + " elements" : detail::json_type_name(a.value())));
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i) {
    out[i] = a.at(i).as<double>();
    if (!(out[i] >= lo && out[i] <= hi)) detail::out_of_bounds(a.at(i).where(), "a number", lo, hi, out[i]);
  }
  return out;
}

template <typename E>
E JsonReader::get_enum(const std::string& key, const std::vector<E>& values) const {
  const std::string s = get<std::string>(key);
  std::string allowed;
  for (E v : values) {
    if (s == to_string(v)) return v;
    allowed += (allowed.empty() ? "\"" : ", \"") + std::string(to_string(v)) + "\"";
  }
  throw InputError(where(key), "expected one of " + allowed + ", got \"" + s + "\"");
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
