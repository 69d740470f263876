# SPDX-License-Identifier: MIT
"""The ParaView GUI with the uvr Volume representation (docs/images/paraview_gui.png): run by
scripts/figures/paraview_gui.sh as `paraview --script=...`, which screenshots the X display."""
import os

from paraview.simple import (ColorBy, GetActiveViewOrCreate, GetColorTransferFunction,
                             Hide3DWidgets, LegacyVTKReader, LoadPlugin, Render,
                             SetActiveSource, Show, Slice)

LoadPlugin(os.environ["UVR_PLUGIN"], ns=globals())
reader = LegacyVTKReader(registrationName="bluntfin_tets.vtk",
                         FileNames=[os.path.join(os.environ["UVR_DATA"], "bluntfin_tets.vtk")])
view = GetActiveViewOrCreate("RenderView")
display = Show(reader, view)
display.SetRepresentationType("uvr Volume")
ColorBy(display, ("POINTS", "density"))
GetColorTransferFunction("density").ApplyPreset("Viridis (matplotlib)", True)
display.UvrMethod = "exact"
s = Slice(registrationName="Slice1", Input=reader)
s.SliceType.Normal = [0.0, 0.0, 1.0]
sd = Show(s, view)
ColorBy(sd, None)
sd.DiffuseColor = [0.9, 0.5, 0.2]
Hide3DWidgets(proxy=s.SliceType)
view.ResetCamera()
view.GetActiveCamera().Azimuth(25)
view.GetActiveCamera().Elevation(25)
view.ResetCamera()
Render(view)
SetActiveSource(reader)  # the panel shows the uvr Volume settings
display.UpdatePropertyInformation()
print("uvr report:", display.GetProperty("UvrLastFrameReport").GetElement(0)[:300])
