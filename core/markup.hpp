// Text into XML, HTML and Markdown tables (JUnit reports of the gate, the run report's HTML,
// the generated references): one escape for every markup driftlab writes.
#pragma once

#include <string>
#include <string_view>

namespace driftlab {

/// Which quotes become entities: both (XML attributes of either kind), or only the double
/// quote (HTML text and double-quoted attributes, where "e'_p" reads better as it is).
enum class MarkupQuotes { kBoth, kDoubleOnly };

/// `text` with & < > " (and with kBoth ') written as entities (&amp; &lt; &gt; &quot;
/// &apos;).
std::string markup_escape(std::string_view text, MarkupQuotes quotes = MarkupQuotes::kBoth);

/// `text` for one cell of a Markdown table: each | written as \\|.
std::string markdown_cell(std::string_view text);

}  // namespace driftlab
