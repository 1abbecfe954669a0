// One field list per JSON record. A record's JSON form is written down once, as a generic lambda over
// the record and a visitor, and both its writer and its strict reader come from that list:
//
//   constexpr auto kRuleFields = [](auto& s, auto& f) {
//     f("low", s.low, Bounds{0, 1});                          // a number in [0, 1]
//     f("mode", s.mode, OneOf{Mode::kA, Mode::kB});            // an enum, spelled by to_string(Mode)
//     f("view_pooling", s.pooling, OmitIf{Pooling::kNone});    // left out while it has that value
//     f("large_prune", s.prune, WhenAbsent{Prune::kOld});      // what an older record without it meant
//     f("mask", s.mask);                                       // a std::optional: absent or null = unset
//   };
//   Json j = json_fields::write(rule, kRuleFields);
//   Rule r = json_fields::read(reader, Rule{}, kRuleFields, json_fields::Absent::kKeep);
//
// The reader marks and type-checks every key, reports keys the list does not name (JsonReader::finish),
// and words every error the JsonReader way ("<file>:<pointer>: expected ..."). A key whose JSON form is
// a choice (a string or an array) is one `f.custom(key, write, read)` entry, with both of its
// conversions side by side: `write()` returns the key's JSON (Json(Json::value_t::discarded) leaves the
// key out) and `read(reader, key)` reads it, marking the key when it is absent.
#pragma once

#include <Eigen/Core>
#include <array>
#include <initializer_list>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "core/json_reader.h"

namespace weathergs::json_fields {

// What a key missing from the JSON means for the whole record.
enum class Absent {
  kError,  // every key is required, unless its entry says otherwise (Optional, WhenAbsent, OmitIf)
  kKeep,   // a missing key keeps the value the record had before reading (its documented default)
  // kKeep for a file a user writes rather than a record: WhenAbsent (what older records meant) does
  // not apply, and a missing key keeps its default there too.
  kDefaults,
};

// Per-entry options; any of them may follow the field, in any order.
struct Bounds {  // a finite number (or each number of an array) within [lo, hi]
  double lo, hi;
};
struct Range {};     // a pair [min, max] that may also be given as one number x, meaning [x, x]
struct Optional {};  // may be missing even from a kError record; keeps its value then
struct WriteNull {};  // a std::optional written as null while unset (instead of left out)
struct EmptyIsNull {};  // a std::string written as null while empty; null or a missing key reads as ""
template <typename E>
struct OneOf {  // the spellings an enum accepts
  std::vector<E> values;
  OneOf(std::initializer_list<E> v) : values(v) {}
};
template <typename T>
struct WhenAbsent {  // always written; a record without the key reads as `value`
  T value;
};
template <typename T>
WhenAbsent(T) -> WhenAbsent<T>;
template <typename T>
struct OmitIf {  // written only when the field differs from `value`; a missing key reads as `value`
  T value;
};
template <typename T>
OmitIf(T) -> OmitIf<T>;

namespace detail {

template <typename T, typename... Opts>
constexpr bool has_option = (std::is_same_v<std::decay_t<Opts>, T> || ...);

template <typename T, typename Opt>
const T* as_option(const Opt& o) {
  if constexpr (std::is_same_v<std::decay_t<Opt>, T>) return &o;
  return nullptr;
}
template <typename T, typename... Opts>
const T* find_option(const Opts&... opts) {
  const T* found = nullptr;
  ((found = found ? found : as_option<T>(opts)), ...);
  return found;
}

template <typename T>
struct is_std_array : std::false_type {};
template <typename U, size_t N>
struct is_std_array<std::array<U, N>> : std::true_type {};
template <typename T>
struct is_vector : std::false_type {};
template <typename U>
struct is_vector<std::vector<U>> : std::true_type {};
template <typename T>
struct is_optional : std::false_type {};
template <typename U>
struct is_optional<std::optional<U>> : std::true_type {};

template <typename T>
Json to_json_value(const T& v) {
  if constexpr (std::is_enum_v<T>) {
    return to_string(v);
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    return Json{v.x(), v.y(), v.z()};
  } else {
    return v;
  }
}

template <typename T, typename... Opts>
T read_value(const JsonReader& r, const std::string& key, const T& current, const Opts&... opts) {
  const Bounds* b = find_option<Bounds>(opts...);
  const double lo = b ? b->lo : -JsonReader::kHuge, hi = b ? b->hi : JsonReader::kHuge;
  if constexpr (std::is_enum_v<T>) {
    const OneOf<T>* values = find_option<OneOf<T>>(opts...);
    static_assert(has_option<OneOf<T>, Opts...>, "an enum entry needs OneOf{...} with its accepted values");
    return r.get_enum(key, values->values);
  } else if constexpr (std::is_floating_point_v<T>) {
    if (b) return T(r.get_number(key, lo, hi));
    return r.get<T>(key);
  } else if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
    const T v = r.get<T>(key);
    if (b && !(double(v) >= lo && double(v) <= hi)) weathergs::detail::out_of_bounds(r.where(key), "an integer", lo, hi, double(v));
    return v;
  } else if constexpr (is_std_array<T>::value) {
    constexpr size_t n = std::tuple_size<T>::value;
    if constexpr (n == 2) {
      if constexpr (has_option<Range, Opts...>) return r.get_range_or(key, current, lo, hi);
    }
    if constexpr (std::is_same_v<typename T::value_type, double>) {
      return r.get_array<n>(key, lo, hi);
    } else {
      const JsonReader a = r.child(key);
      if (!a.is_array() || a.size() != n)
        throw InputError(a.where(), "expected an array of " + std::to_string(n) + " values, got " +
                                        weathergs::detail::json_type_name(a.value()));
      T out{};
      for (size_t i = 0; i < n; ++i) {
        out[i] = a.at(i).template as<typename T::value_type>();
        if (b && !(double(out[i]) >= lo && double(out[i]) <= hi))
          weathergs::detail::out_of_bounds(a.at(i).where(), "a value", lo, hi, double(out[i]));
      }
      return out;
    }
  } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
    const std::array<double, 3> a = r.get_array<3>(key, lo, hi);
    return Eigen::Vector3d(a[0], a[1], a[2]);
  } else {
    return r.get<T>(key);  // bool, std::string, std::vector of those
  }
}

}  // namespace detail

// Builds the JSON object of a record from its field list.
class Writer {
 public:
  template <typename T, typename... Opts>
  void operator()(const char* key, const T& field, const Opts&... opts) {
    if constexpr (detail::is_optional<T>::value) {
      if (field)
        json_[key] = detail::to_json_value(*field);
      else if (detail::has_option<WriteNull, Opts...>)
        json_[key] = nullptr;
    } else {
      if (const auto* omit = detail::find_option<OmitIf<T>>(opts...); omit && field == omit->value) return;
      if constexpr (detail::has_option<EmptyIsNull, Opts...>) {
        if (field.empty()) {
          json_[key] = nullptr;
          return;
        }
      }
      json_[key] = detail::to_json_value(field);
    }
  }
  template <typename Write, typename Read>
  void custom(const char* key, Write&& write, Read&&) {
    Json v = write();
    if (!v.is_discarded()) json_[key] = std::move(v);
  }
  Json take() { return std::move(json_); }

 private:
  Json json_ = Json::object();
};

// Reads a record's keys from a JSON object, strictly.
class Reader {
 public:
  Reader(const JsonReader& r, Absent absent) : r_(r), absent_(absent) {}

  template <typename T, typename... Opts>
  void operator()(const char* key, T& field, const Opts&... opts) {
    const bool present = r_.has(key) && !r_.value()[key].is_null();
    if constexpr (detail::is_optional<T>::value) {
      if (!present) {
        r_.mark(key);
        field.reset();
      } else {
        field = detail::read_value<typename T::value_type>(r_, key, field.value_or(typename T::value_type{}), opts...);
      }
      return;
    } else {
      if (present) {
        field = detail::read_value<T>(r_, key, field, opts...);
        return;
      }
      r_.mark(key);
      const auto* w = detail::find_option<WhenAbsent<T>>(opts...);
      if (w && absent_ != Absent::kDefaults) {
        field = w->value;
      } else if (const auto* o = detail::find_option<OmitIf<T>>(opts...)) {
        field = o->value;
      } else if constexpr (detail::has_option<EmptyIsNull, Opts...>) {
        field.clear();
      } else if (absent_ == Absent::kError && !detail::has_option<Optional, Opts...>) {
        r_.fail(key, "a required key");
      }
    }
  }
  template <typename Write, typename Read>
  void custom(const char* key, Write&&, Read&& read) {
    read(r_, std::string(key));
  }

 private:
  const JsonReader& r_;
  Absent absent_;
};

// `fields(record, visitor)` lists the record's entries; see the top of this file.
template <typename Record, typename Fields>
Json write(const Record& record, const Fields& fields) {
  Record copy = record;  // the list is one lambda for both directions, so it sees a mutable record
  Writer w;
  fields(copy, w);
  return w.take();
}

// Reads into a copy of `prototype` (whose values are the defaults under Absent::kKeep), then checks that
// no key was left unread.
template <typename Record, typename Fields>
Record read(const JsonReader& r, Record prototype, const Fields& fields, Absent absent) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object, got " + weathergs::detail::json_type_name(r.value()));
  Reader reader(r, absent);
  fields(prototype, reader);
  r.finish();
  return prototype;
}

}  // namespace weathergs::json_fields
