#include "core/yaml_io.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <optional>
#include <random>

namespace driftlab::yaml {
namespace {

enum class Color { kRed, kGreen };
constexpr auto enum_table(Color) {
  return std::array{std::pair{Color::kRed, "red"}, std::pair{Color::kGreen, "green"}};
}

struct Inner {
  double x_m = 1.5;
  std::array<double, 3> v{0, 0, 0};
  template <class A>
  void visit(A& a) {
    a("x_m", x_m, "An inner length [m]", positive());
    a("v", v, "A 3-vector");
  }
};

struct Point {
  double a = 0;
  int b = 0;
  template <class A>
  void visit(A& ar) {
    ar("a", a, "first");
    ar("b", b, "second", non_negative());
  }
};

struct Outer {
  std::string name = "default";
  bool flag = false;
  int count = 3;
  std::uint64_t seed = 7;
  double ratio = 0.5;
  Color color = Color::kRed;
  std::vector<double> values{1.0, 2.0};
  std::vector<Color> colors;
  Inner inner;
  std::vector<Point> points;
  int lo = 0;
  int hi = 10;
  template <class A>
  void visit(A& a) {
    a("name", name, "A name", non_empty());
    a("flag", flag, "A flag");
    a("count", count, "A count", in_range(1, 100));
    a("seed", seed, "A seed");
    a("ratio", ratio, "A ratio", unit_interval());
    a("color", color, "A colour");
    a("values", values, "Some values", min_size(1));
    a("colors", colors, "Some colours");
    a("inner", inner, "Nested");
    a("points", points, "A list of mappings");
    a("lo", lo, "Lower");
    a("hi", hi, "Upper");
    a.require(lo < hi, "hi", "hi > lo");
  }
};

Outer read(const std::string& text) {
  Outer o;
  read_into(load_string(text, "test.yaml"), {"test.yaml", true}, &o);
  return o;
}

std::string error_of(const std::string& text) {
  try {
    read(text);
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlReader, ReadsEveryTypeAndKeepsDefaults) {
  const Outer o = read(
      "name: river\nflag: true\ncount: 42\nseed: 18446744073709551615\ncolor: green\n"
      "values: [0.25, -3e2]\ncolors: [green, red]\ninner: {v: [1, 2, 3]}\n"
      "points:\n  - {a: 1.5, b: 2}\n  - {b: 4}\n");
  EXPECT_EQ(o.name, "river");
  EXPECT_TRUE(o.flag);
  EXPECT_EQ(o.count, 42);
  EXPECT_EQ(o.seed, 18446744073709551615ULL);
  EXPECT_EQ(o.ratio, 0.5);  // default kept
  EXPECT_EQ(o.color, Color::kGreen);
  EXPECT_EQ(o.values, (std::vector<double>{0.25, -300.0}));
  EXPECT_EQ(o.colors, (std::vector<Color>{Color::kGreen, Color::kRed}));
  EXPECT_EQ(o.inner.x_m, 1.5);  // default kept inside a nested map
  EXPECT_EQ(o.inner.v, (std::array<double, 3>{1, 2, 3}));
  ASSERT_EQ(o.points.size(), 2u);
  EXPECT_EQ(o.points[0].a, 1.5);
  EXPECT_EQ(o.points[1].a, 0.0);
  EXPECT_EQ(o.points[1].b, 4);
}

TEST(YamlReader, UnknownKeyNamesFileLineKeyAndSuggestion) {
  const std::string e = error_of("name: x\ninner:\n  x_n: 2\n");
  EXPECT_NE(e.find("test.yaml:3:3"), std::string::npos) << e;
  EXPECT_NE(e.find("inner.x_n: unknown key"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'inner.x_m'"), std::string::npos) << e;
}

TEST(YamlReader, WrongTypesAreErrors) {
  EXPECT_NE(error_of("count: abc\n").find("test.yaml:1:8: count: got 'abc', expected an integer"),
            std::string::npos);
  EXPECT_NE(error_of("count: 2.5\n").find("expected an integer"), std::string::npos);
  EXPECT_NE(error_of("ratio: [1]\n").find("ratio: got a list, expected a number"),
            std::string::npos);
  EXPECT_NE(error_of("flag: yes\n").find("flag: got 'yes', expected true or false"),
            std::string::npos);
  EXPECT_NE(error_of("inner: 3\n").find("inner: got '3', expected a mapping"), std::string::npos);
  EXPECT_NE(error_of("seed: -1\n").find("seed: got '-1', expected a non-negative integer"),
            std::string::npos);
  EXPECT_NE(error_of("ratio:\n").find("ratio: got nothing (null), expected a number"),
            std::string::npos);
}

TEST(YamlReader, NonFiniteAndOutOfRangeAreErrors) {
  EXPECT_NE(error_of("ratio: .nan\n").find("ratio: got '.nan', expected a finite number"),
            std::string::npos);
  EXPECT_NE(error_of("ratio: .inf\n").find("expected a finite number"), std::string::npos);
  EXPECT_NE(error_of("ratio: 1.5\n").find("ratio: got 1.5, expected a value in [0, 1]"),
            std::string::npos);
  EXPECT_NE(error_of("inner: {x_m: 0}\n").find("inner.x_m: got 0, expected a value > 0"),
            std::string::npos);
  EXPECT_NE(error_of("count: 3000000000\n").find("expected an integer"), std::string::npos);
}

struct River {
  double width_m = 20;
  template <class A>
  void visit(A& a) {
    a("width_m", width_m, "Width [m]", positive() & up_to(2000, "no river is wider"));
  }
};

TEST(YamlCheck, APlausibleRangeSaysWhyInMessagesAndTheReference) {
  const Check c = positive() & up_to(2000, "no river is wider");
  EXPECT_EQ(c.describe(), "in (0, 2000] (no river is wider)");
  EXPECT_EQ(plausible(-5, 5, "a").describe(), "in [-5, 5] (a)");
  EXPECT_EQ((plausible(0, 9, "a") & up_to(4, "b")).describe(), "in [0, 4] (a; b)");
  EXPECT_EQ(positive().describe(), "> 0");  // no reason, no parentheses
  River r;
  try {
    read_into(YAML::Load("width_m: 1e308"), {"r.yaml", true}, &r);
    ADD_FAILURE() << "1e308 m accepted";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "width_m: got 1e+308, expected a value in (0, 2000] (no river is wider)"),
              std::string::npos)
        << e.what();
  }
  r.width_m = 2500;
  EXPECT_NE(validate(r).find("expected a value in (0, 2000] (no river is wider)"),
            std::string::npos);
  EXPECT_EQ(schema_of(River{}).front().constraint, "in (0, 2000] (no river is wider)");
}

TEST(YamlReader, EnumsListChoices) {
  EXPECT_NE(error_of("color: blue\n").find("color: got 'blue', expected one of: red, green"),
            std::string::npos);
  EXPECT_NE(error_of("colors: [red, bleu]\n").find("colors[1]: got 'bleu'"), std::string::npos);
}

TEST(YamlReader, SequenceSizesAndElements) {
  EXPECT_NE(error_of("values: []\n").find("values: got a list of 0, expected a list of at least 1"),
            std::string::npos);
  EXPECT_NE(error_of("inner: {v: [1, 2]}\n").find("expected a list of exactly 3 values"),
            std::string::npos);
  EXPECT_NE(error_of("points: [{b: -1}]\n").find("points[0].b: got -1, expected a value >= 0"),
            std::string::npos);
}

TEST(YamlReader, CrossFieldRuleAndDuplicateKeys) {
  EXPECT_NE(error_of("lo: 5\nhi: 5\n").find("test.yaml:2:5: hi: got '5', expected hi > lo"),
            std::string::npos);
  EXPECT_NE(error_of("count: 1\ncount: 2\n").find("test.yaml:2:1: count: duplicate key"),
            std::string::npos);
}

TEST(YamlReader, CollectsEveryProblem) {
  const std::string e = error_of("count: 0\nratio: 2\ncolour: red\n");
  EXPECT_NE(e.find("count: got 0"), std::string::npos) << e;
  EXPECT_NE(e.find("ratio: got 2"), std::string::npos) << e;
  EXPECT_NE(e.find("colour: unknown key (did you mean 'color'?)"), std::string::npos) << e;
}

TEST(YamlReader, SyntaxErrorsAndEmptyDocuments) {
  try {
    load_string("a: [1, 2\nb: 3\n", "bad.yaml");
    FAIL() << "expected a syntax error";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("YAML syntax error"), std::string::npos);
  }
  EXPECT_THROW(load_string("", "empty.yaml"), UserError);
  EXPECT_THROW(load_string("# only a comment\n", "empty.yaml"), UserError);
  Outer o;
  EXPECT_THROW(read_into(load_string("- 1\n- 2\n", "list.yaml"), {"list.yaml", true}, &o),
               UserError);
}

TEST(YamlOverride, BuildsNestedDocumentAndAppliesOnTop) {
  Outer o = read("count: 5\ninner: {x_m: 2}\n");
  read_into(override_document("inner.v=[4, 5, 6]"), {"--set inner.v=[4, 5, 6]", false}, &o);
  read_into(override_document("color=green"), {"--set color=green", false}, &o);
  EXPECT_EQ(o.count, 5);
  EXPECT_EQ(o.inner.x_m, 2.0);
  EXPECT_EQ(o.inner.v, (std::array<double, 3>{4, 5, 6}));
  EXPECT_EQ(o.color, Color::kGreen);
  try {
    read_into(override_document("inner.y=1"), {"--set inner.y=1", false}, &o);
    FAIL();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("--set inner.y=1: inner.y: unknown key"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(override_document("novalue"), UserError);
  EXPECT_THROW(override_document("a..b=1"), UserError);
}

TEST(YamlWriter, RoundTripIsExactAndStable) {
  Outer o = read(
      "name: 'with: colon'\nratio: 0.1\nvalues: [0.30000000000000004, 1e-300, -2.5]\n"
      "points: [{a: 3.141592653589793, b: 1}]\ncolors: [green]\n");
  const std::string text = to_yaml(o);
  const Outer back = read(text);
  EXPECT_EQ(back.name, "with: colon");
  EXPECT_EQ(back.ratio, 0.1);
  EXPECT_EQ(back.values, o.values);
  ASSERT_EQ(back.points.size(), 1u);
  EXPECT_EQ(back.points[0].a, 3.141592653589793);
  EXPECT_EQ(to_yaml(back), text);  // writing is a fixed point
}

TEST(YamlWriter, FormatDoubleIsShortestAndBitExact) {
  EXPECT_EQ(format_double(0.1), "0.1");
  EXPECT_EQ(format_double(6.5), "6.5");
  EXPECT_EQ(format_double(-0.0), "-0");
  std::mt19937_64 gen(3);
  for (int i = 0; i < 10000; ++i) {
    std::uint64_t bits = gen();
    double v;
    std::memcpy(&v, &bits, sizeof v);
    if (!std::isfinite(v)) continue;
    double back = 0;
    ASSERT_TRUE(parse_double(format_double(v), &back));
    EXPECT_EQ(std::memcmp(&v, &back, sizeof v), 0) << format_double(v);
  }
}

TEST(YamlValidate, ChecksStructsBuiltInCode) {
  Outer o;
  EXPECT_EQ(validate(o), "");
  o.ratio = std::nan("");
  o.inner.x_m = -1;
  o.hi = -3;
  const std::string e = validate(o);
  EXPECT_NE(e.find("ratio: got nan, expected a finite number"), std::string::npos) << e;
  EXPECT_NE(e.find("inner.x_m: got -1, expected a value > 0"), std::string::npos) << e;
  EXPECT_NE(e.find("hi: expected hi > lo"), std::string::npos) << e;
  EXPECT_THROW(validate_or_throw(o, "Outer"), UserError);
}

TEST(YamlSchema, OneRowPerFieldWithDefaultsAndConstraints) {
  const auto rows = schema_of(Outer{});
  auto find = [&](const std::string& key) -> const SchemaRow* {
    for (const auto& r : rows)
      if (r.key_path == key) return &r;
    return nullptr;
  };
  ASSERT_NE(find("inner.x_m"), nullptr);
  EXPECT_EQ(find("inner.x_m")->default_value, "1.5");
  EXPECT_EQ(find("inner.x_m")->constraint, "> 0");
  EXPECT_EQ(find("ratio")->constraint, "in [0, 1]");
  EXPECT_EQ(find("color")->type, "one of: red, green");
  EXPECT_NE(find("points[].b"), nullptr);
  EXPECT_EQ(find("hi")->constraint, "hi > lo");
  EXPECT_NE(schema_markdown(rows).find("| `inner.x_m` | number | `1.5` | > 0 |"),
            std::string::npos);
}

// ---------------------------------------------------------------------------
// Optional, required, one-of, free-form values and mappings, locations: what sweep files and
// baselines need from the one strict reader.

struct Span {
  double start = 0;
  std::optional<double> step;
  std::string where;
  template <class A>
  void visit(A& a) {
    a.location(&where);
    a("start", start, "Start", required("a number"));
    a("step", step, "Step", positive() & expecting("a step > 0"));
  }
};

struct Spec {
  std::string key;
  std::optional<std::string> label;
  std::optional<std::vector<Any>> values;
  std::optional<Span> span;
  Entries<Any> set;
  std::uint64_t copies = 1;
  std::string where, key_where;
  template <class A>
  void visit(A& a) {
    a.location(&where);
    a.location("key", &key_where);
    a("key", key, "A key path", non_empty() & required("a key path such as a.b"));
    a("label", label, "A label", non_empty());
    a("values", values, "Values as written");
    a("span", span, "A generated span");
    a("set", set, "Fixed values by key path", expecting("a mapping of key paths to values"));
    a("copies", copies, "Copies", expecting("an integer >= 1 (copies)"));
    a.exactly_one_of({"values", "span"});
    a.require(!values || !values->empty(), "values", "at least one value");
    a.require(copies >= 1, "copies", "an integer >= 1 (copies)");
  }
};

Spec read_spec(const std::string& text) {
  Spec s;
  read_into(load_string(text, "spec.yaml"), {"spec.yaml", true}, &s);
  return s;
}

std::string spec_error(const std::string& text) {
  try {
    read_spec(text);
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlReader, OptionalAnyAndEntriesReadAsWrittenWithTheirPlaces) {
  const Spec s =
      read_spec("key: a.b\nvalues: [1, [x, y], {m: 2}]\nset:\n  p.q: 3\n  r: [1, 2]\ncopies: 2\n");
  EXPECT_EQ(s.key, "a.b");
  EXPECT_EQ(s.key_where, "spec.yaml:1:6");
  EXPECT_EQ(s.where, "spec.yaml:1:1");
  EXPECT_FALSE(s.label.has_value());
  EXPECT_FALSE(s.span.has_value());
  ASSERT_TRUE(s.values.has_value());
  ASSERT_EQ(s.values->size(), 3u);
  EXPECT_EQ((*s.values)[0].flow_text(), "1");
  EXPECT_EQ((*s.values)[1].flow_text(), "[x, y]");
  EXPECT_EQ((*s.values)[2].flow_text(), "{m: 2}");
  EXPECT_EQ((*s.values)[1].where, "spec.yaml:2:13");
  ASSERT_EQ(s.set.size(), 2u);
  EXPECT_EQ(s.set[0].key, "p.q");
  EXPECT_EQ(s.set[0].value.flow_text(), "3");
  EXPECT_EQ(s.set[0].where, "spec.yaml:4:3");
  EXPECT_EQ(s.set[1].key, "r");
  EXPECT_EQ(s.set[1].value.flow_text(), "[1, 2]");
  EXPECT_EQ(s.copies, 2u);

  const Spec t = read_spec("key: k\nlabel: L\nspan: {start: 2.5, step: 0.5}\n");
  EXPECT_EQ(t.label, "L");
  ASSERT_TRUE(t.span.has_value());
  EXPECT_EQ(t.span->start, 2.5);
  EXPECT_EQ(t.span->step, 0.5);
  EXPECT_EQ(t.span->where, "spec.yaml:3:7");
  // Null is "not given".
  EXPECT_FALSE(read_spec("key: k\nlabel: ~\nvalues: [1]\n").label.has_value());
}

TEST(YamlReader, RequiredOneOfAndRulesNameWhatIsExpected) {
  // A missing top-level key has no place but the file; a nested one points at its mapping.
  std::string e = spec_error("values: [1]\n");
  EXPECT_NE(e.find("spec.yaml: key: missing, expected a key path such as a.b"), std::string::npos)
      << e;
  e = spec_error("key: k\nspan: {step: 1}\n");
  EXPECT_NE(e.find("spec.yaml:2:7: span.start: missing, expected a number"), std::string::npos)
      << e;
  // Exactly one of: none, and two.
  e = spec_error("key: k\n");
  EXPECT_NE(e.find("spec.yaml:1:1: (top level): got none of values, span, expected exactly one "
                   "of them"),
            std::string::npos)
      << e;
  e = spec_error("key: k\nvalues: [1]\nspan: {start: 0}\n");
  EXPECT_NE(e.find("spec.yaml:3:7: (top level): got both values and span, expected exactly one "
                   "of: values, span"),
            std::string::npos)
      << e;
  // Rules quote the value given (and say what an empty list is).
  e = spec_error("key: k\nvalues: []\ncopies: 0\n");
  EXPECT_NE(e.find("spec.yaml:2:9: values: got an empty list, expected at least one value"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("spec.yaml:3:9: copies: got '0', expected an integer >= 1 (copies)"),
            std::string::npos)
      << e;
  // Custom wording replaces the generated text, for types and bounds alike.
  e = spec_error("key: k\nvalues: [1]\ncopies: -2\nset: [1]\n");
  EXPECT_NE(e.find("copies: got '-2', expected an integer >= 1 (copies)"), std::string::npos) << e;
  EXPECT_NE(e.find("set: got a list, expected a mapping of key paths to values"), std::string::npos)
      << e;
  e = spec_error("key: k\nspan: {start: 0, step: -1}\n");
  EXPECT_NE(e.find("span.step: got '-1', expected a step > 0"), std::string::npos) << e;
  // A value that does not read is not there: no rule fires on a half-read value.
  e = spec_error("key: k\nvalues: 3\n");
  EXPECT_NE(e.find("values: got '3', expected a list"), std::string::npos) << e;
  EXPECT_EQ(e.find("at least one value"), std::string::npos) << e;
  // A required key that is missing is reported once, not again by the rules about it.
  e = spec_error("values: [1]\n");
  EXPECT_EQ(e.find("\n"), std::string::npos) << e;
  // Duplicate names in a free-form mapping.
  e = spec_error("key: k\nvalues: [1]\nset: {a: 1, a: 2}\n");
  EXPECT_NE(e.find("set.a: duplicate key, expected each key once"), std::string::npos) << e;
}

TEST(YamlSchema, OptionalEntriesAndOneOfAppearInTheReference) {
  const auto rows = schema_of(Spec{});
  auto row = [&](const std::string& key) {
    for (const auto& r : rows)
      if (r.key_path == key) return r;
    ADD_FAILURE() << key;
    return SchemaRow{};
  };
  EXPECT_EQ(row("key").constraint, "required, non-empty");
  EXPECT_EQ(row("label").type, "string or null");
  EXPECT_EQ(row("label").default_value, "null");
  EXPECT_EQ(row("set").type, "mapping of names to any value");
  EXPECT_EQ(row("set").default_value, "{}");
  EXPECT_EQ(row("span").type, "mapping or null");
  EXPECT_EQ(row("span.start").constraint, "required");
  EXPECT_EQ(row("values").constraint, "exactly one of values, span; at least one value");
  // The writer writes what it read.
  const Spec s = read_spec("key: a\nvalues: [1, [2, 3]]\nset: {p: x}\n");
  const Spec back = read_spec(to_yaml(s));
  EXPECT_EQ(back.key, "a");
  EXPECT_EQ((*back.values)[1].flow_text(), "[2, 3]");
  EXPECT_EQ(back.set[0].value.flow_text(), "x");
  EXPECT_FALSE(back.label.has_value());
}

// Plug-ins by name, each with an options struct of its own type: "inner" holds an Inner,
// "point" a Point; "plain" is known but has no options.
struct WithPlugins {
  int n = 1;
  NamedOptions plugins{[](const std::string& name) -> std::unique_ptr<NamedOptions::Holder> {
                         if (name == "inner") return make_options<Inner>();
                         if (name == "point") return make_options(Point{.a = 2.5, .b = 1});
                         return nullptr;
                       },
                       [] {
                         return std::vector<std::string>{"inner", "point"};
                       }};
  template <class A>
  void visit(A& a) {
    a("n", n, "A count");
    a("plugins", plugins, "Options by name");
  }
};

std::string error_reading(WithPlugins* w, const std::string& text, const std::string& label) {
  try {
    read_into(load_string(text, label), {label, true}, w);
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

TEST(YamlNamedOptions, EachNameReadsItsOwnTypeAndALaterReadChangesOnlyItsKeys) {
  WithPlugins w;
  EXPECT_TRUE(w.plugins.empty());
  EXPECT_EQ(error_reading(&w, "plugins:\n  point: {b: 4}\n  inner: {x_m: 3}\n", "p.yaml"), "");
  const Point* p = options_of<Point>(w.plugins.find("point"));
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->a, 2.5);  // the maker's default, kept
  EXPECT_EQ(p->b, 4);
  EXPECT_EQ(options_of<Inner>(w.plugins.find("inner"))->x_m, 3.0);
  EXPECT_EQ(options_of<Inner>(w.plugins.find("point")), nullptr);  // another type
  // An override of one key (as --set does) keeps the others and the entries' order.
  read_into(override_document("plugins.point.a=7"), {"--set plugins.point.a=7", false}, &w);
  EXPECT_EQ(options_of<Point>(w.plugins.find("point"))->a, 7.0);
  EXPECT_EQ(options_of<Point>(w.plugins.find("point"))->b, 4);
  EXPECT_EQ(w.plugins.entries()[0].first, "point");
  // A copy is deep: changing it leaves the original as it was.
  WithPlugins copy = w;
  read_into(override_document("plugins.point.b=9"), {"--set plugins.point.b=9", false}, &copy);
  EXPECT_EQ(options_of<Point>(w.plugins.find("point"))->b, 4);
  EXPECT_EQ(options_of<Point>(copy.plugins.find("point"))->b, 9);
  // Written with every field, and read back to the same values.
  const std::string text = to_yaml(w, false);
  EXPECT_NE(text.find("plugins:\n  point:\n    a: 7\n    b: 4\n  inner:\n    x_m: 3\n"),
            std::string::npos)
      << text;
  WithPlugins back;
  EXPECT_EQ(error_reading(&back, text, "back.yaml"), "");
  EXPECT_EQ(to_yaml(back, false), text);
  EXPECT_EQ(to_yaml(WithPlugins{}, false), "n: 1\nplugins: {}\n");
}

TEST(YamlNamedOptions, ErrorsNameTheKeyPathAndTheReferenceListsEveryName) {
  WithPlugins w;
  std::string e = error_reading(&w, "plugins:\n  orb: {x: 1}\n  plain:\n", "p.yaml");
  EXPECT_NE(e.find("p.yaml:2:3: plugins: got 'orb', expected one of: inner, point"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("got 'plain'"), std::string::npos) << e;
  e = error_reading(&w, "plugins:\n  point: {b: -1, c: 2}\n  inner: 3\n", "p.yaml");
  EXPECT_NE(e.find("plugins.point.b: got -1, expected a value >= 0"), std::string::npos) << e;
  EXPECT_NE(e.find("p.yaml:2:18: plugins.point.c: unknown key (did you mean 'plugins.point.a'?)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("p.yaml:3:10: plugins.inner: got '3', expected a mapping of keys to values"),
            std::string::npos)
      << e;
  // Validation of a struct built in code reaches into each name's options.
  WithPlugins bad;
  read_into(override_document("plugins.inner.x_m=1"), {"--set", false}, &bad);
  const_cast<Inner&>(*options_of<Inner>(bad.plugins.find("inner"))).x_m = -1;
  EXPECT_NE(validate(bad).find("plugins.inner.x_m: got -1, expected a value > 0"),
            std::string::npos)
      << validate(bad);
  const auto rows = schema_of(WithPlugins{});
  std::vector<std::string> keys;
  for (const auto& r : rows) keys.push_back(r.key_path);
  EXPECT_EQ(keys, (std::vector<std::string>{"n", "plugins", "plugins.inner", "plugins.inner.x_m",
                                            "plugins.inner.v", "plugins.point", "plugins.point.a",
                                            "plugins.point.b"}));
  EXPECT_EQ(rows[1].constraint, "names: inner, point");
  EXPECT_EQ(rows[6].default_value, "2.5");  // the maker's defaults
}

TEST(YamlHelpers, EditDistance) {
  EXPECT_EQ(edit_distance("kitten", "sitting"), 3u);
  EXPECT_EQ(edit_distance("", "abc"), 3u);
  EXPECT_EQ(edit_distance("same", "same"), 0u);
}

}  // namespace
}  // namespace driftlab::yaml
