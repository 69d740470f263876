// SPDX-License-Identifier: MIT
#include "vtkUvrVolumeRepresentation.h"

#include <string>

#include "uvr/render/settings_vocabulary.h"
#include "vtkColorTransferFunction.h"
#include "vtkDataSet.h"
#include "vtkInformation.h"
#include "vtkObjectFactory.h"
#include "vtkPVLODVolume.h"
#include "vtkPVRenderView.h"
#include "vtkRenderer.h"
#include "vtkUvrVolumeMapper.h"
#include "vtkVolumeProperty.h"
#include "vtkVolumeRepresentationPreprocessor.h"

vtkStandardNewMacro(vtkUvrVolumeRepresentation);

namespace {

constexpr const char* kMapperName = "uvr";

/// Passes a panel value to the mapper's settings by the vocabulary's name; the frame changes.
void applySetting(vtkUvrVolumeRepresentation* self, vtkUvrVolumeMapper* mapper, const char* name,
                  const nlohmann::json& value) {
    mapper->SetUvrSetting(name, value);
    self->Modified();
}

}  // namespace

vtkUvrVolumeRepresentation::vtkUvrVolumeRepresentation() : UvrMapper(vtkUvrVolumeMapper::New()) {
    // Native cells: the preprocessor only gathers the blocks, it splits nothing.
    this->Preprocessor->SetTetrahedraOnly(0);
    this->AddVolumeMapper(kMapperName, this->UvrMapper);
    this->Superclass::SetActiveVolumeMapper(kMapperName);
}

vtkUvrVolumeRepresentation::~vtkUvrVolumeRepresentation() {
    this->UvrMapper->Delete();
}

void vtkUvrVolumeRepresentation::SetActiveVolumeMapper(const char*) {
    this->Superclass::SetActiveVolumeMapper(kMapperName);
}

void vtkUvrVolumeRepresentation::SetMethod(int index) {
    const auto& choices = uvr::settingNamed("method").choices;
    if (index < 0 || index >= int(choices.size())) {
        vtkErrorMacro(<< "uvr Volume: method " << index << ": expected 0 to "
                      << choices.size() - 1);
        return;
    }
    applySetting(this, this->UvrMapper, "method", choices[std::size_t(index)]);
}

void vtkUvrVolumeRepresentation::SetQuality(double quality) {
    applySetting(this, this->UvrMapper, "quality", quality);
}

void vtkUvrVolumeRepresentation::SetSampleDistance(double distance) {
    applySetting(this, this->UvrMapper, "sample_distance",
                 distance > 0.0 ? nlohmann::json(distance) : nlohmann::json());
}

void vtkUvrVolumeRepresentation::SetShade(int on) {
    applySetting(this, this->UvrMapper, "shade", on != 0);
}

void vtkUvrVolumeRepresentation::SetAmbient(double v) {
    applySetting(this, this->UvrMapper, "ambient", v);
}

void vtkUvrVolumeRepresentation::SetDiffuse(double v) {
    applySetting(this, this->UvrMapper, "diffuse", v);
}

void vtkUvrVolumeRepresentation::SetSpecular(double v) {
    applySetting(this, this->UvrMapper, "specular", v);
}

void vtkUvrVolumeRepresentation::SetSpecularPower(double v) {
    applySetting(this, this->UvrMapper, "specular_power", v);
}

void vtkUvrVolumeRepresentation::SetSupersample(int n) {
    applySetting(this, this->UvrMapper, "supersample", n);
}

void vtkUvrVolumeRepresentation::SetDevice(int index) {
    static const char* const kDevices[] = {"auto", "cpu", "cuda"};
    if (index < 0 || index > 2) {
        vtkErrorMacro(<< "uvr Volume: device " << index
                      << ": expected 0 (auto), 1 (cpu) or 2 (cuda)");
        return;
    }
    this->UvrMapper->SetUvrDevice(kDevices[index]);
    this->MarkModified();
}

void vtkUvrVolumeRepresentation::SetSplitCells(int on) {
    this->UvrMapper->SetUvrSplitCells(on != 0);
    this->MarkModified();
}

void vtkUvrVolumeRepresentation::SetClip(int on) {
    this->Clip = on != 0;
    this->UpdateClip();
}

void vtkUvrVolumeRepresentation::SetClipOrigin(double x, double y, double z) {
    this->ClipOrigin[0] = x, this->ClipOrigin[1] = y, this->ClipOrigin[2] = z;
    this->UpdateClip();
}

void vtkUvrVolumeRepresentation::SetClipNormal(double x, double y, double z) {
    this->ClipNormal[0] = x, this->ClipNormal[1] = y, this->ClipNormal[2] = z;
    this->UpdateClip();
}

void vtkUvrVolumeRepresentation::SetClipSurface(int on) {
    applySetting(this, this->UvrMapper, "clip_surface", on != 0);
}

void vtkUvrVolumeRepresentation::UpdateClip() {
    this->UvrMapper->SetUvrClipPlane(this->Clip, this->ClipOrigin, this->ClipNormal);
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetNumberOfIsoValues(int n) {
    this->IsoValues.resize(std::size_t(n < 0 ? 0 : n), 0.0);
    this->UpdateIsoSurfaces();
}

void vtkUvrVolumeRepresentation::SetIsoValue(int i, double value) {
    if (i < 0) return;
    if (std::size_t(i) >= this->IsoValues.size()) this->IsoValues.resize(std::size_t(i) + 1);
    this->IsoValues[std::size_t(i)] = value;
    this->UpdateIsoSurfaces();
}

void vtkUvrVolumeRepresentation::SetIsoOpacity(double opacity) {
    this->IsoOpacity = opacity;
    this->UpdateIsoSurfaces();
}

void vtkUvrVolumeRepresentation::UpdateIsoSurfaces() {
    this->UvrMapper->SetUvrIsoSurfaces(this->IsoValues, this->IsoOpacity);
    this->Modified();
}

const char* vtkUvrVolumeRepresentation::GetLastFrameReport() {
    this->LastReport = this->UvrMapper->LastReport();
    return this->LastReport.c_str();
}

void vtkUvrVolumeRepresentation::ReportProgress(void* self, const char* step, double fraction) {
    // ParaView's progress bar shows the algorithm's progress text and fraction.
    auto* me = static_cast<vtkUvrVolumeRepresentation*>(self);
    if (step) me->SetProgressText((std::string("uvr: ") + step).c_str());
    me->UpdateProgress(fraction);
}

int vtkUvrVolumeRepresentation::RequestData(vtkInformation* request,
                                            vtkInformationVector** inputVector,
                                            vtkInformationVector* outputVector) {
    if (!this->Superclass::RequestData(request, inputVector, outputVector)) return 0;
    // Prepare here, where ParaView shows the pipeline's progress, rather than at the first
    // frame (Render prepares what is still missing, e.g. after the array changed).
    auto* data = vtkDataSet::SafeDownCast(this->Preprocessor->GetOutputDataObject(0));
    if (data && data->GetNumberOfCells() > 0) {
        this->UpdateMapperParameters();
        this->UvrMapper->Prepare(data, &vtkUvrVolumeRepresentation::ReportProgress, this);
    }
    return 1;
}

void vtkUvrVolumeRepresentation::UpdateMapperParameters() {
    this->Superclass::UpdateMapperParameters();
    // The component the colour map reads (ParaView's Magnitude / X / Y / Z).
    vtkColorTransferFunction* ctf = this->Property->GetRGBTransferFunction(0);
    if (ctf) this->UvrMapper->SetUvrVectorMode(ctf->GetVectorMode(), ctf->GetVectorComponent());
    // With translucent geometry in the view (a slice's plane widget), VTK's depth peeling would
    // render volumes inside its peels, where the mapper's frame does not belong: volumes are
    // rendered after the translucent geometry instead (docs/PARAVIEW.md).
    if (auto* view = vtkPVRenderView::SafeDownCast(this->GetView()))
        if (vtkRenderer* ren = view->GetRenderer()) ren->SetUseDepthPeelingForVolumes(false);
}
