"""Renders a regolith run's VTK frames with ParaView, as a check that ParaView reads them.

    regolith run scenes/impact_tipped_coarse.ron --out out/impact --vtk 0.01
    xvfb-run -a pvpython scripts/paraview_render.py out/impact docs/paraview_impact_coarse.png

Opens <run>/vtk/points.pvd (every body a block of one multiblock data set), moves the
time slider to the frame nearest 0.1 s, colours the points by pressure and saves the view
as the PNG given, with the frame's time in its title.
"""
import sys

from paraview.simple import (
    ColorBy,
    GetActiveViewOrCreate,
    GetAnimationScene,
    GetColorTransferFunction,
    GetScalarBar,
    GetParaViewVersion,
    PVDReader,
    ResetCamera,
    SaveScreenshot,
    Show,
    Text,
)

run, png = sys.argv[1], sys.argv[2]
PV = GetParaViewVersion()
reader = PVDReader(FileName=f"{run}/vtk/points.pvd")
times = list(reader.TimestepValues)
print(f"{len(times)} frames from t = {times[0]:g} s to {times[-1]:g} s")
scene = GetAnimationScene()
scene.UpdateAnimationUsingDataTimeSteps()

view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [1200, 800]
view.OrientationAxesVisibility = 0
view.UseColorPaletteForBackground = 0
view.Background = [1, 1, 1]
display = Show(reader, view)
display.SetRepresentationType("Points")
display.PointSize = 3
ColorBy(display, ("POINTS", "pressure"))
lut = GetColorTransferFunction("pressure")
lut.ApplyPreset("Viridis (matplotlib)", True)
lut.RescaleTransferFunction(0.0, 20000.0)
display.SetScalarBarVisibility(view, True)
bar = GetScalarBar(lut, view)
bar.TitleColor = bar.LabelColor = [0, 0, 0]
bar.Title = "pressure (Pa)"
bar.ComponentTitle = ""
label = Text()
label_display = Show(label, view)
label_display.FontSize = 14
label_display.Color = [0, 0, 0]
label_display.WindowLocation = "Upper Center"

view.CameraParallelProjection = 1
view.InteractionMode = "2D"
ResetCamera(view)
pick = min(times, key=lambda t: abs(t - 0.1))
label.Text = f"regolith run {run}: pressure (Pa) at t = {pick:.3f} s (ParaView {PV.major}.{PV.minor})"
scene.AnimationTime = pick
view.ViewTime = pick
SaveScreenshot(png, view, ImageResolution=[1200, 800])
print(f"wrote {png} at t = {pick:g} s")
