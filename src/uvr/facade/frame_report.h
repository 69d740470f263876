// SPDX-License-Identifier: MIT
#pragma once

#include <nlohmann/json.hpp>

#include "uvr/facade/renderer.h"

namespace uvr {

/// One frame's report (issue 30): every figure of a rendered frame as one JSON object, lengths
/// and positions in the file's units. The CLI's --stats file, Python's `stats` and the viewer's
/// frame messages are this object; each front end adds only what it alone knows (the CLI the
/// source file and the mesh check, the viewer its encoding). docs/STATS.md lists every key.
///
/// Keys: field, field_association, device, threads, gpu (on the GPU), method (auto resolved),
/// method_asked and method_reason (auto), sampling (not exact), partitions, seed_grids,
/// tf_update_seconds, max_sample_distance, step_rule, quality and tolerance (error rule) or power
/// (variance rule), skip, adaptive, partitions_visited and partitions_skipped (meshes with
/// partitions), image, supersample, jitter (supersampled), rays, mesh, prepare_seconds,
/// render_seconds, samples, mean_samples_per_pixel, mean_samples_per_ray, max_samples_per_pixel,
/// samples_per_second, walk_steps, bvh_queries, step, opacity_unit, opacity_law, range,
/// log_scale, tf_table_entries, camera, notes, empty_frame.
nlohmann::json frameReport(const Renderer& renderer, const RenderSettings& settings,
                           const RenderResult& result);

/// A length or coordinate in the file's units for a report: a float where it fits (as the file
/// gives them), else a double (the default camera of a mesh near 1e38 lies beyond float's range).
nlohmann::json reportNumber(double v);

}  // namespace uvr
