// SPDX-License-Identifier: MIT
#pragma once

#include "uvr/render/frame_setup.h"

namespace uvr {

/// Renders a frame on all CPU cores with the integrator settings.method names.
RenderResult renderCpu(const PreparedMesh& mesh, const RenderSettings& settings);

}  // namespace uvr
