// SPDX-License-Identifier: MIT
#pragma once

// "uvr Volume": ParaView's unstructured-grid volume representation with uvr as its one mapper.
// Everything the "Volume" representation reads (the selected array, the colour map and opacity
// function with their range and log scale, the opacity unit distance, blocks of a multiblock
// input) reaches uvr unchanged; cells stay native (no split into tetrahedra). The panel's uvr
// settings are the library's vocabulary (uvr/render/settings_vocabulary.h): each setter passes
// its value to it by the vocabulary's name, which checks and stores it.

#include <string>
#include <vector>

#include "vtkUnstructuredGridVolumeRepresentation.h"
#include "vtkUvrVolumeRepresentationModule.h"  // for the export macro

class vtkUvrVolumeMapper;

class VTKUVRVOLUMEREPRESENTATION_EXPORT vtkUvrVolumeRepresentation
    : public vtkUnstructuredGridVolumeRepresentation {
public:
    static vtkUvrVolumeRepresentation* New();
    vtkTypeMacro(vtkUvrVolumeRepresentation, vtkUnstructuredGridVolumeRepresentation);

    /// The mapper is always uvr's (ParaView's "SelectMapper" choice is kept but not used).
    void SetActiveVolumeMapper(const char* name) override;

    /// Integrator, the vocabulary's `method` choices by index (auto, adaptive, reference, exact).
    void SetMethod(int index);
    /// The error rule's target SSIM (`quality`).
    void SetQuality(double quality);
    /// Sample distance s1 in the data's units (`sample_distance`); 0: the default.
    void SetSampleDistance(double distance);
    /// Gradient shading (`shade`) and its coefficients (`ambient`, `diffuse`, `specular`,
    /// `specular_power`), the last four shared with the surface representation's Lighting.
    void SetShade(int on);
    void SetAmbient(double v);
    void SetDiffuse(double v);
    void SetSpecular(double v);
    void SetSpecularPower(double v);
    /// Anti-aliasing: N x N rays per pixel (`supersample`).
    void SetSupersample(int n);
    /// Where frames render: 0 auto, 1 cpu, 2 cuda.
    void SetDevice(int index);
    /// Split hexahedra, wedges and pyramids into tetrahedra as ParaView's mappers do.
    void SetSplitCells(int on);
    /// One clip plane through the origin, keeping the side the normal points to; the cut face
    /// drawn as a surface with ClipSurface (`clip_surface`).
    void SetClip(int on);
    void SetClipOrigin(double x, double y, double z);
    void SetClipNormal(double x, double y, double z);
    void SetClipSurface(int on);
    /// Isosurfaces inside the volume at these values, of one opacity, coloured by the map.
    void SetNumberOfIsoValues(int n);
    void SetIsoValue(int i, double value);
    void SetIsoOpacity(double opacity);

    /// The last frame's report (the library's frame report, docs/STATS.md) as JSON text.
    const char* GetLastFrameReport();

protected:
    vtkUvrVolumeRepresentation();
    ~vtkUvrVolumeRepresentation() override;

    int RequestData(vtkInformation* request, vtkInformationVector** inputVector,
                    vtkInformationVector* outputVector) override;
    void UpdateMapperParameters() override;

private:
    vtkUvrVolumeRepresentation(const vtkUvrVolumeRepresentation&) = delete;
    void operator=(const vtkUvrVolumeRepresentation&) = delete;
    void UpdateClip();
    void UpdateIsoSurfaces();
    static void ReportProgress(void* self, const char* step, double fraction);

    vtkUvrVolumeMapper* UvrMapper;  // owned
    bool Clip = false;
    double ClipOrigin[3] = {0.0, 0.0, 0.0};
    double ClipNormal[3] = {1.0, 0.0, 0.0};
    std::vector<double> IsoValues;
    double IsoOpacity = 1.0;
    std::string LastReport;
};
