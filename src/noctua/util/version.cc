#include "noctua/util/version.h"

namespace noctua {

std::string Version() { return NOCTUA_VERSION_STRING; }

}  // namespace noctua
