#include "furuta/daemon/rig_connection.hpp"
#include "furuta_build_info.hpp"

namespace furuta::daemon {

const char* const kSoftwareVersion = "furuta " FURUTA_VERSION " (git " FURUTA_GIT_COMMIT ")";

}  // namespace furuta::daemon
