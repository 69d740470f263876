// SPDX-License-Identifier: MIT
#pragma once

/// The uvr library facade: everything an application needs to read, render and write.
#include "uvr/core/error.h"
#include "uvr/core/file_util.h"
#include "uvr/core/output_file.h"
#include "uvr/cpu/cpu_renderer.h"
#include "uvr/cuda/cuda_build.h"
#include "uvr/cuda/cuda_renderer.h"
#include "uvr/mesh/field_select.h"
#include "uvr/mesh/io/mesh_reader.h"
#include "uvr/mesh/mesh.h"
#include "uvr/mesh/procedural.h"
#include "uvr/mesh/refine.h"
#include "uvr/mesh/tet_mesh.h"
#include "uvr/mesh/validate.h"
#include "uvr/render/camera.h"
#include "uvr/render/heatmap.h"
#include "uvr/render/image.h"
#include "uvr/render/image_metrics.h"
#include "uvr/render/plot.h"
#include "uvr/render/render_setup.h"
#include "uvr/tf/transfer_function.h"
