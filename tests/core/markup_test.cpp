// The one markup escape of the gate's JUnit XML and the run report's HTML.
#include "core/markup.hpp"

#include <gtest/gtest.h>

namespace driftlab {
namespace {

TEST(Markup, EscapesTheFiveXmlSpecialCharactersAndNothingElse) {
  EXPECT_EQ(markup_escape(R"(a < b && c > "d" 'e')"),
            "a &lt; b &amp;&amp; c &gt; &quot;d&quot; &apos;e&apos;");
  EXPECT_EQ(markup_escape("plain text 1.5 m/m, ü"), "plain text 1.5 m/m, ü");
  EXPECT_EQ(markup_escape(""), "");
  EXPECT_EQ(markup_escape("&amp;"), "&amp;amp;");  // escaping is not idempotent, by design
  EXPECT_EQ(markup_escape(R"(e'_p "x")", MarkupQuotes::kDoubleOnly), "e'_p &quot;x&quot;");
}

}  // namespace
}  // namespace driftlab
