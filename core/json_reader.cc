#include "core/json_reader.h"

#include <fstream>
#include <sstream>

namespace weathergs {

namespace detail {
std::string json_type_name(const Json& j) {
  if (j.is_null()) return "null";
  if (j.is_boolean()) return "a boolean (" + j.dump() + ")";
  if (j.is_number()) return "a number (" + j.dump() + ")";
  if (j.is_string()) return "a string (" + j.dump() + ")";
  if (j.is_array()) return "an array";
  return "an object";
}
}  // namespace detail

Json read_json_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return Json::parse(ss.str());
  } catch (const Json::exception& e) {  // parse_error, and out_of_range for numbers beyond double (1e400)
    throw InputError(path, std::string("malformed JSON: ") + e.what());
  }
}

std::string settings_mismatch(const Json& recorded, const Json& expected) {
  for (const auto& [key, value] : expected.items()) {
    const Json held = recorded.contains(key) ? recorded[key] : Json();
    if (held != value) return key + ": holds " + held.dump() + ", asked for " + value.dump();
  }
  return "";
}

JsonReader::JsonReader(const Json& value, std::string file, std::string pointer)
    : value_(&value), file_(std::move(file)), pointer_(std::move(pointer)) {}

JsonReader JsonReader::from_file(const std::string& path) {
  auto doc = std::make_shared<Json>(read_json_file(path));
  JsonReader r(*doc, path, "");
  r.owned_ = doc;
  return r;
}

std::string JsonReader::where(const std::string& key) const {
  std::string p = pointer_;
  if (!key.empty()) p += "/" + key;
  if (p.empty()) p = "/";
  return file_ + ":" + p;
}

bool JsonReader::has(const std::string& key) const {
  return value_->is_object() && value_->contains(key);
}

void JsonReader::fail(const std::string& key, const std::string& expected) const {
  if (!has(key)) throw InputError(where(key), "missing " + expected);
  throw InputError(where(key), "expected " + expected + ", got " +
                                   detail::json_type_name((*value_)[key]));
}

JsonReader JsonReader::child(const std::string& key) const {
  if (!value_->is_object()) throw InputError(where(), "expected an object");
  if (!has(key)) fail(key, "a required key");
  const Json& c = (*value_)[key];
  if (!c.is_object() && !c.is_array()) fail(key, "an object or an array");
  mark(key);
  JsonReader r(c, file_, pointer_ + "/" + key);
  r.owned_ = owned_;
  return r;
}

JsonReader JsonReader::at(size_t index) const {
  if (!value_->is_array()) throw InputError(where(), "expected an array");
  if (index >= value_->size())
    throw InputError(where(), "index " + std::to_string(index) + " out of range");
  JsonReader r((*value_)[index], file_, pointer_ + "/" + std::to_string(index));
  r.owned_ = owned_;
  return r;
}

std::vector<std::string> JsonReader::keys() const {
  std::vector<std::string> k;
  if (value_->is_object())
    for (auto it = value_->begin(); it != value_->end(); ++it) k.push_back(it.key());
  return k;
}

void JsonReader::finish() const {
  if (!value_->is_object()) return;
  std::string unknown;
  for (auto it = value_->begin(); it != value_->end(); ++it)
    if (!used_->count(it.key())) unknown += (unknown.empty() ? "" : ", ") + ("'" + it.key() + "'");
  if (!unknown.empty()) throw InputError(where(), "unknown key(s) " + unknown);
}

namespace detail {
std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void out_of_bounds(const std::string& where, const std::string& what, double lo, double hi, double v) {
  std::string rule = what;
  if (lo > -JsonReader::kHuge || hi < JsonReader::kHuge)
    rule += " in [" + (lo > -JsonReader::kHuge ? format_number(lo) : "-inf") + ", " +
            (hi < JsonReader::kHuge ? format_number(hi) : "inf") + "]";
  else
    rule = "a finite " + what.substr(what.rfind(' ') + 1);
  throw InputError(where, "expected " + rule + ", got " + format_number(v));
}
}  // namespace detail

double JsonReader::get_number(const std::string& key, double lo, double hi) const {
  const double v = get<double>(key);
  if (!(v >= lo && v <= hi)) detail::out_of_bounds(where(key), "a number", lo, hi, v);
  return v;
}

double JsonReader::get_number_or(const std::string& key, double fallback, double lo, double hi) const {
  if (!has(key) || (*value_)[key].is_null()) {
    mark(key);
    return fallback;
  }
  return get_number(key, lo, hi);
}

std::array<double, 2> JsonReader::get_range_or(const std::string& key, const std::array<double, 2>& fallback,
                                               double lo, double hi) const {
  if (!has(key) || (*value_)[key].is_null()) {
    mark(key);
    return fallback;
  }
  if ((*value_)[key].is_number()) {
    const double v = get_number(key, lo, hi);
    return {v, v};
  }
  mark(key);
  const Json& v = (*value_)[key];
  if (!v.is_array() || v.size() != 2)
    throw InputError(where(key), "expected a number or [min, max], got " + detail::json_type_name(v));
  JsonReader a = child(key);
  const std::array<double, 2> r = get_array<2>(key, lo, hi);
  if (!(r[0] <= r[1]))
    throw InputError(a.where(), "expected [min, max] with min <= max, got [" + detail::format_number(r[0]) + ", " +
                                    detail::format_number(r[1]) + "]");
  return r;
}

}  // namespace weathergs
