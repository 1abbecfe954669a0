// The field-list visitor: a record's writer and strict reader come from one list, and reading what it
// wrote gives the record back.
#include "core/json_fields.h"

#include <gtest/gtest.h>

#include <optional>

#include "core/error.h"

namespace weathergs {
namespace {

using namespace json_fields;

enum class Mode { kA, kB, kC };
const char* to_string(Mode m) { return m == Mode::kA ? "a" : m == Mode::kB ? "b" : "c"; }

struct Record {
  int count = 3;
  double rate = 0.5;
  uint64_t seed = 7;
  bool on = true;
  std::string name = "x";
  Mode mode = Mode::kA;
  Mode legacy = Mode::kB;
  Mode pooling = Mode::kA;
  std::array<double, 2> range = {1, 2};
  std::array<double, 3> rgb = {0, 0, 0};
  std::vector<int> steps = {1, 2};
  Eigen::Vector3d dir = Eigen::Vector3d::UnitZ();
  std::optional<double> maybe;
  std::optional<std::string> mask;
  int derived = 0;
  double lo = 0, hi = 1;
};

constexpr auto kFields = [](auto& s, auto& f) {
  f("count", s.count, Bounds{0, 10});
  f("rate", s.rate, Bounds{0, 1});
  f("seed", s.seed);
  f("on", s.on);
  f("name", s.name);
  f("mode", s.mode, OneOf{Mode::kA, Mode::kB, Mode::kC});
  f("legacy", s.legacy, OneOf{Mode::kA, Mode::kB, Mode::kC}, WhenAbsent{Mode::kC});
  f("pooling", s.pooling, OneOf{Mode::kA, Mode::kB, Mode::kC}, OmitIf{Mode::kA});
  f("range", s.range, Range{}, Bounds{0, 100});
  f("rgb", s.rgb);
  f("steps", s.steps);
  f("dir", s.dir);
  f("maybe", s.maybe);
  f("mask", s.mask, WriteNull{});
  f("derived", s.derived, WhenAbsent{s.count * 10});  // may depend on an entry listed before it
  f.custom(
      "interval", [&] { return Json{s.lo, s.hi}; },
      [&](const JsonReader& r, const std::string& k) {
        if (!r.has(k)) return r.mark(k);
        const auto v = r.get_array<2>(k);
        s.lo = v[0], s.hi = v[1];
      });
};

Record read_text(const std::string& text, Absent absent, Record prototype = {}) {
  const Json j = Json::parse(text);
  return read(JsonReader(j, "rec.json"), prototype, kFields, absent);
}

std::string error_of(const std::string& text, Absent absent) {
  try {
    read_text(text, absent);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(JsonFieldsTest, WritesEveryEntryOnceAndReadsItBack) {
  Record r;
  r.count = 9, r.rate = 0.25, r.seed = 1ull << 60, r.on = false, r.name = "y", r.mode = Mode::kC;
  r.legacy = Mode::kA, r.pooling = Mode::kB, r.range = {3, 4}, r.rgb = {0.1, 0.2, 0.3}, r.steps = {5};
  r.dir = {1, 2, 3}, r.maybe = 2.5, r.mask = "masks", r.derived = 4, r.lo = -2, r.hi = 5;
  const Json j = write(r, kFields);
  EXPECT_EQ(j["mode"], "c");
  EXPECT_EQ(j["pooling"], "b");
  EXPECT_EQ(j["seed"].get<uint64_t>(), 1ull << 60);
  EXPECT_EQ(j["interval"], (Json{-2.0, 5.0}));
  const Record back = read(JsonReader(j, "rec.json"), Record{}, kFields, Absent::kError);
  EXPECT_EQ(write(back, kFields), j);
  EXPECT_EQ(back.dir, r.dir);
  EXPECT_EQ(back.mask, r.mask);
}

TEST(JsonFieldsTest, OptionalsAndDefaultsAreLeftOutOrNull) {
  const Json j = write(Record{}, kFields);
  EXPECT_FALSE(j.contains("maybe"));    // unset: left out
  EXPECT_TRUE(j.at("mask").is_null());  // unset with WriteNull: null
  EXPECT_FALSE(j.contains("pooling"));  // at its OmitIf value
  EXPECT_EQ(j.at("legacy"), "b");       // WhenAbsent entries are always written
}

TEST(JsonFieldsTest, MissingKeysFollowTheRecordsRuleAndTheEntrysOptions) {
  Record proto;
  proto.count = 5;
  const Record kept = read_text("{}", Absent::kKeep, proto);
  EXPECT_EQ(kept.count, 5);            // the prototype's value
  EXPECT_EQ(kept.legacy, Mode::kC);    // what a record without the key meant
  EXPECT_EQ(kept.pooling, Mode::kA);   // the OmitIf value
  EXPECT_EQ(kept.derived, 50);         // from the count read before it
  EXPECT_FALSE(kept.maybe.has_value());
  EXPECT_EQ(read_text(R"({"count": 2, "mask": null})", Absent::kKeep).derived, 20);
  EXPECT_NE(error_of("{}", Absent::kError).find("rec.json:/count: missing a required key"), std::string::npos)
      << error_of("{}", Absent::kError);
}

TEST(JsonFieldsTest, BadValuesNameTheKeyAndTheRule) {
  const Absent k = Absent::kKeep;
  EXPECT_NE(error_of(R"({"count": 11})", k).find("/count: expected an integer in [0, 10], got 11"), std::string::npos)
      << error_of(R"({"count": 11})", k);
  EXPECT_NE(error_of(R"({"rate": 2})", k).find("/rate"), std::string::npos);
  EXPECT_NE(error_of(R"({"count": 1.5})", k).find("expected an integer"), std::string::npos);
  EXPECT_NE(error_of(R"({"mode": "d"})", k).find(R"(expected one of "a", "b", "c", got "d")"), std::string::npos);
  EXPECT_NE(error_of(R"({"rgb": [1, 2]})", k).find("/rgb: expected an array of 3 numbers"), std::string::npos);
  EXPECT_NE(error_of(R"({"range": [0, 200]})", k).find("/range/1"), std::string::npos) << error_of(R"({"range": [0, 200]})", k);
  EXPECT_NE(error_of(R"({"name": 3})", k).find("/name: expected a string"), std::string::npos);
  EXPECT_NE(error_of(R"({"cuont": 3})", k).find("cuont"), std::string::npos);  // unknown keys are errors
  EXPECT_NE(error_of("[]", k).find("expected an object"), std::string::npos);
}

TEST(JsonFieldsTest, ARangeMayBeOneNumber) {
  EXPECT_EQ(read_text(R"({"range": 7})", Absent::kKeep).range, (std::array<double, 2>{7, 7}));
  EXPECT_EQ(read_text(R"({"range": [2, 3]})", Absent::kKeep).range, (std::array<double, 2>{2, 3}));
}

}  // namespace
}  // namespace weathergs
