// SPDX-License-Identifier: MIT
#pragma once

#include <string_view>

namespace uvr::server {

/// A file of the page (web/), embedded in the binary at build time.
struct WebAsset {
    std::string_view name;  ///< file name, as requested after "/"
    std::string_view mime;  ///< Content-Type
    std::string_view content;
};

/// The embedded file of that name, or null.
const WebAsset* findWebAsset(std::string_view name);

}  // namespace uvr::server
