// The one seam between toposlamd and the frame sources: openFrameSource(uri) from toposlam_sources
// (io/source_factory.hpp) when that library is built; otherwise a clear error.
#pragma once

#include <memory>
#include <string>

#include "toposlam/pipeline/frame_source.hpp"

namespace toposlam::daemon {

/// "" when `uri` is a source URI toposlamd can open (syntax, known scheme; nothing is opened), else the
/// problem. --check-config uses it.
std::string checkSourceUri(const std::string& uri);

/// The source a map records (io/source_uri.hpp, sourceIdentity): scheme and location, no query.
std::string mapSourceOf(const std::string& uri);

/// Throws FrameSourceError (or std::invalid_argument for a malformed URI) with an actionable message.
std::unique_ptr<FrameSource> openSource(const std::string& uri);

}  // namespace toposlam::daemon
