// Where toposlamd's config is found when no -c is given, so `toposlamd` and `toposlam listen` read the same
// file: $CONFIGURATION_DIRECTORY/toposlam.yaml (systemd ConfigurationDirectory=), then
// /etc/toposlam/toposlam.yaml, then the copy `cmake --install` put under its sysconfdir.
#pragma once

#include <string>

namespace toposlam {

/// The first candidate that exists; the first candidate when none does (so messages name a real place).
std::string defaultDaemonConfigPath();

}  // namespace toposlam
