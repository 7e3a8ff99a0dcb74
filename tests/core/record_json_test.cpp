#include "core/record_json.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace driftlab::record_json {
namespace {

enum class Colour { kRed, kGreen };
constexpr auto enum_table(Colour) {
  return std::array{std::pair{Colour::kRed, "red"}, std::pair{Colour::kGreen, "green"}};
}

struct RjInner {
  double x = 0;
  std::vector<double> values;
  template <class A>
  void visit(A& a) {
    a("x", x, "a number [m]");
    a("values", values, "numbers");
  }
};

struct RjFlat {
  int extra = 0;
  template <class A>
  void visit(A& a) {
    a("extra", extra, "laid out in its owner's object");
  }
};

struct RjRecord {
  bool flag = false;
  std::uint64_t count = 0;
  std::int64_t offset = 0;
  std::string name;
  Colour colour = Colour::kRed;
  std::array<double, 2> pair{0, 0};
  RjInner inner;
  std::map<std::string, RjInner> by_name;
  std::optional<std::string> note;
  std::optional<RjInner> maybe;
  RjFlat flat;
  template <class A>
  void visit(A& a) {
    a("flag", flag, "a flag");
    a("count", count, "a count");
    a("offset", offset, "an offset");
    a("name", name, "a name");
    a("colour", colour, "a colour");
    a("pair", pair, "two numbers");
    a("inner", inner, "a nested record");
    a("by_name", by_name, "records by name");
    a("note", note, "a note, when there is one");
    a("maybe", maybe, "a record, when there is one");
    flat.visit(a);
  }
};

RjRecord sample() {
  RjRecord r;
  r.flag = true;
  r.count = 7;
  r.offset = -3;
  r.name = "a|b";
  r.colour = Colour::kGreen;
  r.pair = {0.5, -1.25};
  r.inner = {2.5, {1, 2}};
  r.by_name["b"] = {1, {}};
  r.by_name["a"] = {2, {3}};
  r.note = "n";
  r.flat.extra = 4;
  return r;
}

// The JSON written by hand from the record's fields: keys sorted, optionals absent when empty,
// a member's fields laid out flat.
TEST(RecordJson, WritesEveryFieldTypeAsHandWrittenJson) {
  const nlohmann::json expected = nlohmann::json::parse(R"({
    "flag": true, "count": 7, "offset": -3, "name": "a|b", "colour": "green",
    "pair": [0.5, -1.25], "inner": {"x": 2.5, "values": [1.0, 2.0]},
    "by_name": {"a": {"x": 2.0, "values": [3.0]}, "b": {"x": 1.0, "values": []}},
    "note": "n", "extra": 4})");
  EXPECT_EQ(to_json(sample()).dump(), expected.dump());
}

TEST(RecordJson, ReadsBackWhatItWrote) {
  const RjRecord r = from_json<RjRecord>(to_json(sample()), "m.json");
  EXPECT_EQ(to_json(r).dump(), to_json(sample()).dump());
  EXPECT_EQ(r.colour, Colour::kGreen);
  EXPECT_EQ(r.by_name.at("a").values, std::vector<double>{3});
  EXPECT_FALSE(r.maybe.has_value());
  EXPECT_EQ(r.flat.extra, 4);
}

TEST(RecordJson, NamesEachNumberWrittenAsNullAndReadsNullAsNaN) {
  RjRecord r = sample();
  r.inner.values[1] = std::numeric_limits<double>::quiet_NaN();
  r.by_name["a"].x = -std::numeric_limits<double>::infinity();
  std::vector<NonFinite> nonfinite;
  const nlohmann::json j = to_json(r, &nonfinite);
  EXPECT_TRUE(j["inner"]["values"][1].is_null());
  ASSERT_EQ(nonfinite.size(), 2u);
  EXPECT_EQ(nonfinite[0].key, "inner.values[1]");
  EXPECT_EQ(nonfinite[1].key, "by_name.a.x");
  EXPECT_TRUE(std::isinf(nonfinite[1].value));
  const RjRecord back = from_json<RjRecord>(j, "m.json");
  EXPECT_TRUE(std::isnan(back.inner.values[1]));
  EXPECT_TRUE(std::isnan(back.by_name.at("a").x));  // null: not a number any more
}

// A number written as null (not finite) in an optional stays there: read back as NaN, written
// again as null.
struct RjMaybeNumber {
  std::optional<double> r2;
  template <class A>
  void visit(A& a) {
    a("r2", r2, "R^2");
  }
};

TEST(RecordJson, AnOptionalNumberWrittenAsNullReadsBackAsNaN) {
  RjMaybeNumber r;
  r.r2 = std::numeric_limits<double>::quiet_NaN();
  const nlohmann::json j = to_json(r);
  EXPECT_EQ(j.dump(), R"({"r2":null})");
  const auto back = from_json<RjMaybeNumber>(j, "m.json");
  ASSERT_TRUE(back.r2.has_value());
  EXPECT_TRUE(std::isnan(*back.r2));
  EXPECT_EQ(to_json(back).dump(), j.dump());
}

TEST(RecordJson, KeepsDefaultsForAbsentKeysAndReadsNullOptionalsAsEmpty) {
  const auto r =
      from_json<RjRecord>(nlohmann::json::parse(R"({"name": "x", "maybe": null})"), "old.json");
  EXPECT_EQ(r.name, "x");
  EXPECT_EQ(r.count, 0u);
  EXPECT_FALSE(r.maybe.has_value());
}

std::string read_error(const std::string& text) {
  try {
    from_json<RjRecord>(nlohmann::json::parse(text), "run/metrics.json");
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(RecordJson, RefusesWrongTypesAndUnknownKeysNamingFileKeyValueAndExpectation) {
  EXPECT_EQ(read_error(R"({"count": -1})"),
            "run/metrics.json: count: got -1, expected a whole number >= 0");
  EXPECT_EQ(read_error(R"({"inner": {"values": [1, "2"]}})"),
            "run/metrics.json: inner.values[1]: got \"2\", expected a number or null");
  EXPECT_EQ(read_error(R"({"colour": "blue"})"),
            "run/metrics.json: colour: got \"blue\", expected one of red, green");
  EXPECT_EQ(read_error(R"({"pair": [1]})"),
            "run/metrics.json: pair: got [1], expected a list of 2");
  EXPECT_EQ(read_error(R"({"by_name": {"a": {"x": 1, "y": 2}}})"),
            "run/metrics.json: by_name.a.y: unknown key, expected one of: values, x");
  EXPECT_EQ(read_error(R"({"offset": 9223372036854775808})"),
            "run/metrics.json: offset: got 9223372036854775808, expected a whole number from "
            "-9223372036854775808 to 9223372036854775807");
  EXPECT_EQ(read_error(R"({"flag": 1})"), "run/metrics.json: flag: got 1, expected true or false");
}

TEST(RecordJson, DocumentsEveryKeyWithItsTypeAndMeaning) {
  const std::vector<FieldRow> rows = fields_of<RjRecord>();
  auto find = [&](const std::string& key) -> const FieldRow* {
    for (const auto& r : rows)
      if (r.key_path == key) return &r;
    return nullptr;
  };
  ASSERT_NE(find("by_name.NAME.x"), nullptr);
  EXPECT_EQ(find("by_name.NAME.x")->doc, "a number [m]");
  EXPECT_EQ(find("by_name")->type, "object of names to object");
  EXPECT_EQ(find("maybe")->type, "object or absent");
  EXPECT_EQ(find("maybe.values")->type, "list of number");
  EXPECT_EQ(find("colour")->type, "one of: red, green");
  EXPECT_EQ(find("pair")->type, "list of 2 number");
  EXPECT_EQ(find("extra")->doc, "laid out in its owner's object");
  EXPECT_EQ(rows.size(), 17u);
  EXPECT_NE(fields_markdown(rows).find("| `name` | string | a name |"), std::string::npos);
}

// Named<T>: an object whose keys keep the order they were added in.
struct RjOrdered {
  std::string zeta = "z";
  Named<Named<int>> by_run;
  double alpha = 1;
  template <class A>
  void visit(A& a) {
    a("zeta", zeta, "first in the list");
    a("by_run", by_run, "counts by run and name");
    a("alpha", alpha, "last in the list");
  }
};

TEST(RecordJson, TheOrderedWriterKeepsTheVisitOrderAndTheNamesOrder) {
  RjOrdered r;
  r.by_run["r2"]["b"] = 1;
  r.by_run["r1"]["a"] = 2;
  r.by_run["r2"]["a"] = 3;  // an existing name keeps its place
  EXPECT_EQ(to_ordered_json(r).dump(),
            R"({"zeta":"z","by_run":{"r2":{"b":1,"a":3},"r1":{"a":2}},"alpha":1.0})");
  EXPECT_EQ(to_json(r).dump(),
            R"({"alpha":1.0,"by_run":{"r1":{"a":2},"r2":{"a":3,"b":1}},"zeta":"z"})");
  // Read from an ordered document, the names come back in the file's order.
  const auto back = from_json<RjOrdered>(to_ordered_json(r), "o.json");
  EXPECT_EQ(to_ordered_json(back).dump(), to_ordered_json(r).dump());
  ASSERT_NE(back.by_run.find("r2"), nullptr);
  EXPECT_EQ(back.by_run.find("r2")->items.front().first, "b");
  EXPECT_EQ(back.by_run.find("r3"), nullptr);
  const std::vector<FieldRow> rows = fields_of<RjOrdered>();
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1].type, "object of names (in order) to object of names (in order) to integer");
}

TEST(RecordJson, ANewerWritersKeysCanBeLeftAsideAndRequiredKeysListed) {
  const auto j = nlohmann::json::parse(R"({"name": "x", "inner": {"x": 1, "later": 2}, "new": 3})");
  EXPECT_THROW(from_json<RjRecord>(j, "m.json"), UserError);
  const auto r = from_json<RjRecord>(j, "m.json", UnknownKeys::kIgnore);
  EXPECT_EQ(r.name, "x");
  EXPECT_EQ(r.inner.x, 1);
  EXPECT_EQ(missing_keys<RjOrdered>(nlohmann::json::parse(R"({"by_run": {}})")),
            (std::vector<std::string>{"zeta", "alpha"}));
  EXPECT_EQ(missing_keys<RjOrdered>(nlohmann::json::parse("[]")).size(), 3u);
}

TEST(RecordJson, ParseJsonNamesTheSourceAndWhatWasExpected) {
  try {
    parse_json("{\"a\": ", "sweep/sweep.json", "a sweep plan");
    FAIL() << "no error";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("sweep/sweep.json: not valid JSON (", 0), 0u) << what;
    EXPECT_NE(what.find("), expected a sweep plan"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace driftlab::record_json
