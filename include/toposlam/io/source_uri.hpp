// Parsing of frame-source URIs: `scheme:path?key=value&key=value`. Typed getters throw FrameSourceError
// naming the key, the bad value and the allowed range, so a typo in a URI tells the user what to fix.
//
// A path may itself contain '?' (a glob wildcard): the query starts at the LAST '?' whose remainder looks
// like key=value pairs. A string without a scheme (no "name:" prefix of letters, digits, '_' or '-') is a
// plain path and gets an empty scheme. Plain value type: thread-safe for const use.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

namespace toposlam {

struct SourceUri {
  std::string text;    ///< the URI as given
  std::string scheme;  ///< lower case, e.g. "images"; empty for a plain path
  std::string path;    ///< what follows "scheme:" up to the query
  std::map<std::string, std::string> query;

  bool has(const std::string& key) const { return query.count(key) != 0; }
  std::string getString(const std::string& key, const std::string& fallback) const;
  /// One of `allowed`; throws naming the key and listing the allowed values otherwise.
  std::string getChoice(const std::string& key, const std::string& fallback, const std::vector<std::string>& allowed) const;
  double getDouble(const std::string& key, double fallback, double min_value, double max_value) const;
  long long getInt(const std::string& key, long long fallback, long long min_value, long long max_value) const;
  /// "1|0|true|false|yes|no|on|off".
  bool getBool(const std::string& key, bool fallback) const;
  /// "WxH", e.g. 320x240; each side in [min_side, max_side].
  std::pair<int, int> getSize(const std::string& key, std::pair<int, int> fallback, int min_side = 16,
                              int max_side = 8192) const;
  /// Throws FrameSourceError naming the first query key not in `allowed` (the common key "rate" is
  /// always allowed) and listing the allowed keys.
  void requireOnly(const std::vector<std::string>& allowed) const;
};

/// Throws FrameSourceError on an empty URI, an empty key or a duplicated key.
SourceUri parseSourceUri(const std::string& uri);

/// `uri` with the relative path of a file source (`images:`, `video:` or a plain path) made absolute and
/// normalised, its query kept; other schemes unchanged. Run folders record their sources this way so
/// `toposlam report` finds the frames from any working directory.
std::string absoluteSourceUri(const std::string& uri);

/// What a map records as the source it was made from: the scheme and location without the query
/// ("sim:office", "v4l2:/dev/video0", "images:/abs/folder"; file paths absolute as in absoluteSourceUri, a
/// plain path as "images:PATH"). Rate, size, route and other query keys do not make another source.
std::string sourceIdentity(const std::string& uri);

}  // namespace toposlam
