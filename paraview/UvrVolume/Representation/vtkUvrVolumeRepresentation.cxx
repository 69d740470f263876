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

/// A value as the vocabulary's JSON text.
std::string jsonText(double v) {
    return nlohmann::json(v).dump();
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
    this->UvrMapper->SetUvrSetting("method", nlohmann::json(choices[std::size_t(index)]).dump());
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetQuality(double quality) {
    this->UvrMapper->SetUvrSetting("quality", jsonText(quality));
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetSampleDistance(double distance) {
    this->UvrMapper->SetUvrSetting("sample_distance",
                                   distance > 0.0 ? jsonText(distance) : std::string("null"));
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetShade(int on) {
    this->UvrMapper->SetUvrSetting("shade", on ? "true" : "false");
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetAmbient(double v) {
    this->UvrMapper->SetUvrSetting("ambient", jsonText(v));
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetDiffuse(double v) {
    this->UvrMapper->SetUvrSetting("diffuse", jsonText(v));
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetSpecular(double v) {
    this->UvrMapper->SetUvrSetting("specular", jsonText(v));
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetSpecularPower(double v) {
    this->UvrMapper->SetUvrSetting("specular_power", jsonText(v));
    this->Modified();
}

void vtkUvrVolumeRepresentation::SetSupersample(int n) {
    this->UvrMapper->SetUvrSetting("supersample", std::to_string(n));
    this->Modified();
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
    this->UvrMapper->SetUvrSetting("clip_surface", on ? "true" : "false");
    this->Modified();
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
