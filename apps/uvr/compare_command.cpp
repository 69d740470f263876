// SPDX-License-Identifier: MIT
#include "cli_common.h"

namespace uvr::cli {
void addCompareCommand(CLI::App&, Log&) {}
}  // namespace uvr::cli
