# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# The demo's scene pictures rendered by ParaView (pvbatch, offscreen): the
# tissue surface coloured by strain between the organ surfaces (translucent),
# at rest and at the end of the run, from a named anatomical view.
#   pvbatch tools/plots/demo_paraview.py DIR/paraview/run.pvd OUT_DIR TITLE VIEW
# VIEW: sagittal (from the patient's left; HRA meshes: +y superior, +z
# anterior, +x left), coronal (from the front, HRA), coronal-ras (from the
# front; label maps: +x right, +y anterior, +z superior).
# Writes OUT_DIR/scene-rest.png and OUT_DIR/scene-deformed.png.
import os
import sys

import paraview.simple as pvs

ORGAN_COLOURS = [(0.79, 0.48, 0.61), (0.85, 0.69, 0.23), (0.50, 0.64, 0.42), (0.54, 0.54, 0.79), (0.71, 0.51, 0.35),
                 (0.37, 0.66, 0.66), (0.62, 0.62, 0.62), (0.88, 0.48, 0.22), (0.42, 0.56, 0.83), (0.64, 0.79, 0.31)]
# camera direction (from the scene towards the camera) and up, per view
VIEWS = {"sagittal": ((1, 0, 0), (0, 1, 0)), "coronal": ((0, 0, 1), (0, 1, 0)), "coronal-ras": ((0, 1, 0), (0, 0, 1))}
ZOOM = {"coronal-ras": 1.6}  # a CT's field of view is wide and flat


def main(pvd, out_dir, title, view):
    reader = pvs.PVDReader(FileName=pvd)
    times = reader.TimestepValues
    render = pvs.CreateView("RenderView")
    render.ViewSize = [1200, 900]
    render.OrientationAxesVisibility = 1
    render.Background = [1, 1, 1]
    try:
        render.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    blocks = pvs.servermanager.Fetch(reader)
    block_names = [blocks.GetMetaData(k).Get(blocks.NAME()) for k in range(blocks.GetNumberOfBlocks())]
    organs = [n for n in block_names if n not in ("tissue", "samples", "frames")]
    shown = []
    for k, name in enumerate(block_names):
        if name in ("samples", "frames"):
            continue
        part = pvs.ExtractBlock(Input=reader, Selectors=["/Root/" + name])
        display = pvs.Show(pvs.MergeBlocks(Input=part), render)
        if name == "tissue":
            pvs.ColorBy(display, ("POINTS", "strain"))
            lut = pvs.GetColorTransferFunction("strain")
            lut.ApplyPreset("Cool to Warm", True)
            display.SetScalarBarVisibility(render, True)
            bar = pvs.GetScalarBar(lut, render)
            bar.Title = "tissue strain (Green-Lagrange |E|)"
            bar.ComponentTitle = ""
            bar.TitleColor = bar.LabelColor = [0, 0, 0]
            tissue_lut = lut
        else:
            display.DiffuseColor = ORGAN_COLOURS[organs.index(name) % len(ORGAN_COLOURS)]
            display.AmbientColor = display.DiffuseColor
            display.Opacity = 0.35
        shown.append(display)
    direction, up = VIEWS[view]
    text = pvs.Text(Text="")
    text_display = pvs.Show(text, render)
    text_display.Color = [0, 0, 0]
    text_display.FontSize = 14
    text_display.WindowLocation = "Upper Center"
    # one colour scale for both pictures: 0 to the largest strain at the end
    reader.UpdatePipeline(times[-1])
    end = pvs.servermanager.Fetch(reader)
    tissue = end.GetBlock(block_names.index("tissue"))
    while tissue.IsA("vtkMultiBlockDataSet"):
        tissue = tissue.GetBlock(0)
    tissue_lut.RescaleTransferFunction(0.0, max(1e-12, tissue.GetPointData().GetArray("strain").GetRange()[1]))
    for stage, t, file in (("at rest", times[0], "scene-rest.png"), ("deformed, end of the run", times[-1],
                                                                      "scene-deformed.png")):
        render.ViewTime = t
        text.Text = "%s: %s, t = %.3g s (%s view; organs translucent)" % (title, stage, t, view)
        render.ResetCamera()
        camera = render.GetActiveCamera()
        focal = camera.GetFocalPoint()
        distance = camera.GetDistance()
        camera.SetPosition([focal[i] + distance * direction[i] for i in range(3)])
        camera.SetViewUp(up)
        render.ResetCamera()
        camera.Zoom(ZOOM.get(view, 1.2))  # the bounding sphere leaves room: fill the picture
        if not pvs.SaveScreenshot(out_dir + "/" + file, render, ImageResolution=[1200, 900]):
            return 1
    return 0


if __name__ == "__main__":
    status = main(*sys.argv[1:5])
    sys.stdout.flush()
    # under Xvfb the OpenGL context's teardown fails (GLXBadContext) after the
    # pictures are written: leave without it
    os._exit(status)
