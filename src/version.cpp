#include "tripodal/version.hpp"

namespace tripodal {

const char* version_string() noexcept { return "0.1.0"; }

}  // namespace tripodal
