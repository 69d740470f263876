// SPDX-License-Identifier: MIT
#pragma once

// The volume mapper of the "uvr Volume" representation: renders its unstructured grid with the
// library's Renderer (prepared once per geometry and field association, values refreshed when
// only they change) and composites the frame over the opaque geometry already drawn, whose
// depth buffer ends its rays. Private to the plugin: no uvr type appears in this header, so the
// wrapped representation header stays free of the library's.

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vtkUnstructuredGridVolumeMapper.h"

class vtkUvrVolumeMapper : public vtkUnstructuredGridVolumeMapper {
public:
    static vtkUvrVolumeMapper* New();
    vtkTypeMacro(vtkUvrVolumeMapper, vtkUnstructuredGridVolumeMapper);

    /// Renders the input into the renderer's viewport over what it holds; errors go to
    /// ParaView's output window and leave the viewport unchanged.
    void Render(vtkRenderer* ren, vtkVolume* vol) override;
    void ReleaseGraphicsResources(vtkWindow* window) override;

    /// A setting of the library's vocabulary by name and value (JSON null: its default); a
    /// refused value is reported and the setting keeps its value.
    void SetUvrSetting(const std::string& name, const nlohmann::json& value);
    /// Where frames render and whether cells are split into tetrahedra: "auto", "cpu", "cuda"
    /// (RendererOptions::device, splitCells); a change prepares the mesh again.
    void SetUvrDevice(const std::string& device);
    void SetUvrSplitCells(bool split);
    /// One clip plane (file coordinates; the side the normal points to is kept) or none.
    void SetUvrClipPlane(bool on, const double origin[3], const double normal[3]);
    /// Isosurfaces at these values, each of this opacity, coloured by the transfer function.
    void SetUvrIsoSurfaces(const std::vector<double>& values, double opacity);
    /// The field's components as ParaView's colour map reads them: VTK's vtkScalarsToColors
    /// vector mode (MAGNITUDE or COMPONENT) and component.
    void SetUvrVectorMode(int mode, int component);

    /// Prepares the input for the selected array now (the representation calls this when its
    /// data changes); `progress` hears each phase's name as it starts (fraction 0) and how far
    /// the phase has come (name null, fraction in [0, 1]). Returns false after reporting an
    /// error.
    bool Prepare(vtkDataSet* input,
                 void (*progress)(void* client, const char* step, double fraction), void* client);
    /// The last frame's report (the library's frameReport) as JSON text, or an error message
    /// {"error": "..."} when the last frame failed; "{}" before any frame.
    const std::string& LastReport() const;

protected:
    vtkUvrVolumeMapper();
    ~vtkUvrVolumeMapper() override;

private:
    vtkUvrVolumeMapper(const vtkUvrVolumeMapper&) = delete;
    void operator=(const vtkUvrVolumeMapper&) = delete;
    struct Internals;
    std::unique_ptr<Internals> internals_;
};
