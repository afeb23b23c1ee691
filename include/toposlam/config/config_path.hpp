// Where a program's config is found when no -c is given, so `toposlamd` and `toposlam listen` read the same
// file, and toposlam-bridge its own: $CONFIGURATION_DIRECTORY/<file> (systemd ConfigurationDirectory=), then
// <sysconfdir>/toposlam/<file> of the install the running program belongs to (found from the program's own
// path, so a tree installed with any --prefix reads its own config), then /etc/toposlam/<file>.
#pragma once

#include <string>
#include <vector>

namespace toposlam {

/// The sysconfdir of the install holding `executable` (<prefix>/bin/NAME or <prefix>/sbin/NAME), by the
/// rule `cmake --install` applies (cmake/ToposlamInstallConfig.cmake): /etc for the prefix /usr (and /),
/// /etc/opt/X for /opt/X, else <prefix>/etc. "" when the executable is in no bin or sbin folder (a build
/// tree).
std::string installSysconfDir(const std::string& executable);

/// The candidates for `file_name` ("toposlam.yaml"), in order, for a program at `executable` ("" = none).
std::vector<std::string> configPathCandidates(const std::string& file_name, const std::string& executable);

/// The first candidate for `file_name` that exists, for the running program; the first candidate when
/// none does (so messages name a real place).
std::string defaultConfigPath(const std::string& file_name);

/// toposlamd's config: defaultConfigPath("toposlam.yaml").
std::string defaultDaemonConfigPath();

}  // namespace toposlam
