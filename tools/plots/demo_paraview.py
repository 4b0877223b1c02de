# SPDX-License-Identifier: MIT
# SPDX-FileCopyrightText: fascia developers
# The demo's scene pictures rendered by ParaView (pvbatch, offscreen): the
# tissue surface coloured by strain between the organ surfaces (translucent),
# at rest and at the end of the run, from a named anatomical view. Strain is
# a magnitude: a sequential map (Viridis) from 0 to the largest sample
# strain at the end (the run's summary's "largest strain", whose value the
# bar's top label shows); organs named in a legend in their colours; the
# deformed picture draws the tissue and the organs at rest in grey
# wireframe behind them, so the motion shows.
#   pvbatch tools/plots/demo_paraview.py DIR/paraview/run.pvd OUT_DIR TITLE VIEW
# VIEW: sagittal (from the patient's left; HRA meshes: +y superior, +z
# anterior, +x left), coronal (from the front, HRA), coronal-ras (from the
# front; label maps: +x right, +y anterior, +z superior).
# Writes OUT_DIR/scene-rest.png and OUT_DIR/scene-deformed.png; prints the colour bar's range.
import os
import sys
import xml.etree.ElementTree as ET

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
    organs = [n for n in block_names if n not in ("tissue", "tetrahedra", "samples", "frames")]
    # a part whose file is the same at the first and the last time (a fixed organ) never moved
    listed = [d.attrib for d in ET.parse(pvd).getroot().iter("DataSet")]
    first = {d["name"]: d["file"] for d in listed if float(d["timestep"]) == times[0]}
    last = {d["name"]: d["file"] for d in listed if float(d["timestep"]) == times[-1]}
    rest_shown = []
    for k, name in enumerate(block_names):
        if name in ("tetrahedra", "samples", "frames"):
            continue
        part = pvs.MergeBlocks(Input=pvs.ExtractBlock(Input=reader, Selectors=["/Root/" + name]))
        # the part at rest (the first time), drawn in the deformed picture only
        if first.get(name) != last.get(name):
            rest = pvs.Show(pvs.ForceTime(Input=part, ForcedTime=times[0], IgnorePipelineTime=1), render)
            rest.ColorArrayName = ["POINTS", ""]  # grey, not the active scalars
            rest.SetRepresentationType("Wireframe")
            rest.AmbientColor = rest.DiffuseColor = [0.45, 0.45, 0.45]
            rest.Opacity = 0.2 if name != "tissue" else 0.5
            rest_shown.append(rest)
        display = pvs.Show(part, render)
        if name == "tissue":
            pvs.ColorBy(display, ("POINTS", "strain"))
            lut = pvs.GetColorTransferFunction("strain")
            lut.ApplyPreset("Viridis (matplotlib)", True)
            display.SetScalarBarVisibility(render, True)
            bar = pvs.GetScalarBar(lut, render)
            bar.Title = "tissue strain |E| (0 to the largest at the end)"
            bar.ComponentTitle = ""
            bar.TitleColor = bar.LabelColor = [0, 0, 0]
            bar.AddRangeLabels = 1  # the top label is the largest strain
            bar.RangeLabelFormat = "%-#.3g"
            tissue_lut = lut
        else:
            display.DiffuseColor = ORGAN_COLOURS[organs.index(name) % len(ORGAN_COLOURS)]
            display.AmbientColor = display.DiffuseColor
            display.Opacity = 0.35
    # the organs' legend: each name in its colour
    for k, name in enumerate(organs):
        label = pvs.Show(pvs.Text(Text=name), render)
        label.Color = ORGAN_COLOURS[k % len(ORGAN_COLOURS)]
        label.FontSize = 16
        label.Bold = 1
        label.WindowLocation = "Any Location"
        label.Position = [0.02, 0.90 - 0.04 * k]
    note_source = pvs.Text(Text="")
    note = pvs.Show(note_source, render)
    note.Color = [0.35, 0.35, 0.35]
    note.FontSize = 12
    note.WindowLocation = "Lower Left Corner"
    direction, up = VIEWS[view]
    text = pvs.Text(Text="")
    text_display = pvs.Show(text, render)
    text_display.Color = [0, 0, 0]
    text_display.FontSize = 14
    text_display.WindowLocation = "Upper Center"
    # one colour scale for both pictures: 0 to the largest sample strain at
    # the end, the quantity the run's summary reports (the surface's own
    # strain, of the sample nearest each vertex, may stay below it)
    reader.UpdatePipeline(times[-1])
    end = pvs.servermanager.Fetch(reader)
    samples = end.GetBlock(block_names.index("samples"))
    while samples.IsA("vtkMultiBlockDataSet"):
        samples = samples.GetBlock(0)
    largest = samples.GetPointData().GetArray("strain").GetRange()[1]
    tissue_lut.RescaleTransferFunction(0.0, max(1e-12, largest))
    print("strain colour bar: 0 to %.6g" % largest)  # the run's summary prints its largest strain so
    tissue_lut.AutomaticRescaleRangeMode = "Never"
    for stage, t, file in (("at rest", times[0], "scene-rest.png"), ("deformed, end of the run", times[-1],
                                                                      "scene-deformed.png")):
        render.ViewTime = t
        deformed = t != times[0]
        for rest in rest_shown:
            rest.Visibility = 1 if deformed else 0
        note_source.Text = "grey wireframe: tissue and organs at rest" if deformed else ""
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
