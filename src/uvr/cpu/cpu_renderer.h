// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/render/render_setup.h"

namespace uvr {

/// Renders a frame with the reference marcher on all CPU cores.
RenderResult renderReferenceCpu(const PreparedMesh& mesh, const RenderSettings& settings);

}  // namespace uvr
