// SPDX-License-Identifier: MIT
#pragma once

#include <nlohmann/json.hpp>

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "uvr/render/camera.h"
#include "uvr/render/frame_setup.h"
#include "uvr/tf/transfer_function.h"

namespace uvr::server {

/// Smallest and largest side of a viewer image.
inline constexpr int kMinViewSize = 16;
inline constexpr int kMaxViewSize = 4096;
/// Most colour or opacity points a tab's transfer function may have (sent as rows or uploaded as
/// a colour map).
inline constexpr std::size_t kMaxTfPoints = 4096;

/// The settings of the library's vocabulary (settings_vocabulary.h) that the page sets, by name:
/// a setting joins the viewer with its name here and a control on the page (which reads its
/// choices, range and doc from the `info` message). The others are the command line's.
inline constexpr std::array<const char*, 11> kViewerSettings{
    "method",  "quality", "opacity_unit", "opacity_law",    "shade",       "normals",
    "ambient", "diffuse", "specular",     "specular_power", "clip_surface"};

/// True for a name of kViewerSettings.
bool isViewerSetting(std::string_view name);

/// What one browser tab looks at (docs/VIEWER.md, "The session state"): everything a frame
/// depends on that the page may change. Positions are in the file's coordinates.
struct ViewState {
    Camera camera;
    TransferFunction tf;
    std::pair<float, float> range{0.f, 1.f};  ///< the data range the transfer function spans
    std::string field;                        ///< as --field takes it
    /// The values of kViewerSettings, as the vocabulary writes them (checked when set); a
    /// setting absent here is the command line's. The server sets opacity_unit to ParaView's
    /// ScalarOpacityUnitDistance (file units) when the command line gives none.
    nlohmann::json settings = nlohmann::json::object();
    bool heatmap = false;  ///< show samples per pixel instead of the volume
    /// Clip planes (file coordinates; RenderSettings::clipPlanes), up to kMaxClipPlanes.
    std::vector<ClipPlane> clipPlanes;
    /// Isosurfaces (RenderSettings::isoSurfaces), up to kMaxIsoSurfaces; the protocol writes
    /// each as `--iso` does: "VALUE[,OPACITY[,#RRGGBB]]".
    std::vector<IsoSurface> isoSurfaces;
    /// The gradient opacity (RenderSettings::lighting's; off unless set); the protocol writes it
    /// as `--gradient-opacity` does, "MAGNITUDE:SCALE,...", or "" when off.
    GradientOpacity gradientOpacity;
    int width = 1024, height = 1024;
    std::size_t step = 0;  ///< the time step shown (0 for a file without time steps)
    /// What frames and snapshots composite over (r, g, b in [0, 1]; `--background`, black by
    /// default): the saved PNG is what the page showed.
    Vec3f background{0.f, 0.f, 0.f};
};

/// The state as the protocol's JSON object.
nlohmann::json toJson(const ViewState& state);

/// What applying a `set` message changed.
struct SetResult {
    bool fieldChanged = false;  ///< `field` names another field (the caller resolves it)
    bool rangeGiven = false;    ///< the message set `range`
    /// The server changed or completed the state beyond what the page sent (a preset, an
    /// uploaded colour map): the page needs the whole state back.
    bool echoState = false;
};

/// Applies the state keys of a `set` message (camera, tf, range, field, method, quality,
/// heatmap, clip_planes, iso, size, background, opacity_unit, opacity_law, step (below
/// stepCount), preset,
/// colormap_json and colormap_name) to `state`, all or
/// nothing: on any bad value it throws Error(Argument) (Error(Parse) for a malformed uploaded
/// colour map) naming the key and what was expected, and leaves `state` unchanged. Unknown keys
/// are refused too (a misspelt key must not pass silently); `type`, `seq` and `interactive`
/// are the caller's.
SetResult applySet(ViewState& state, const nlohmann::json& message, std::size_t stepCount = 1);

/// The render settings of a frame of the state: `base` (what the command line set beyond the
/// state: steps, sampling, rule) with the state's camera, transfer function, range and settings,
/// at the state's size divided by `scale` (at least 1 pixel a side).
RenderSettings frameSettings(const ViewState& state, const RenderSettings& base, int scale = 1);

}  // namespace uvr::server
