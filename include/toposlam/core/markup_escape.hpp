// Escaping text for XML and HTML output (SVG figures, the HTML report): the five characters that
// would otherwise end an element or an attribute. Stateless; thread-safe.
#pragma once

#include <string>

namespace toposlam {

/// `text` with & < > " ' replaced by their entities; safe in element content and quoted attributes.
std::string escapeMarkup(const std::string& text);

}  // namespace toposlam
