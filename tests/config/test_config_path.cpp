// The default config look-up (config_path.hpp): the install's own sysconfdir, found from the program's
// path, whatever prefix it was installed with (it was the configure-time /usr/local/etc before).
#include <catch2/catch.hpp>

#include <cstdlib>
#include <string>
#include <vector>

#include "toposlam/config/config_path.hpp"

using namespace toposlam;

SCENARIO("config path: the sysconfdir follows the prefix the program is installed under") {
  CHECK(installSysconfDir("/usr/sbin/toposlamd") == "/etc");
  CHECK(installSysconfDir("/usr/bin/toposlam-bridge") == "/etc");
  CHECK(installSysconfDir("/usr/local/sbin/toposlamd") == "/usr/local/etc");
  CHECK(installSysconfDir("/home/robot/tsl/bin/toposlam-bridge") == "/home/robot/tsl/etc");
  CHECK(installSysconfDir("/home/robot/tsl/bin/../sbin/toposlamd") == "/home/robot/tsl/etc");
  CHECK(installSysconfDir("/opt/toposlam/bin/toposlam") == "/etc/opt/toposlam");
  CHECK(installSysconfDir("/work/build/src/apps/toposlamd/toposlamd").empty());  // a build tree
  CHECK(installSysconfDir("toposlamd").empty());
}

SCENARIO("config path: candidates are the unit's directory, the install's own, then /etc/toposlam") {
  GIVEN("no CONFIGURATION_DIRECTORY") {
    unsetenv("CONFIGURATION_DIRECTORY");
    CHECK(configPathCandidates("toposlam.yaml", "/srv/tsl/sbin/toposlamd") ==
          std::vector<std::string>{"/srv/tsl/etc/toposlam/toposlam.yaml", "/etc/toposlam/toposlam.yaml"});
    CHECK(configPathCandidates("toposlam-bridge.yaml", "/usr/bin/toposlam-bridge") ==
          std::vector<std::string>{"/etc/toposlam/toposlam-bridge.yaml"});
    CHECK(configPathCandidates("toposlam.yaml", "") ==
          std::vector<std::string>{"/etc/toposlam/toposlam.yaml"});
  }
  GIVEN("systemd's CONFIGURATION_DIRECTORY with two entries") {
    setenv("CONFIGURATION_DIRECTORY", "/etc/toposlam:/etc/other", 1);
    CHECK(configPathCandidates("toposlam-bridge.yaml", "/usr/local/bin/toposlam-bridge") ==
          std::vector<std::string>{"/etc/toposlam/toposlam-bridge.yaml",
                                   "/usr/local/etc/toposlam/toposlam-bridge.yaml",
                                   "/etc/toposlam/toposlam-bridge.yaml"});
    unsetenv("CONFIGURATION_DIRECTORY");
  }
}
