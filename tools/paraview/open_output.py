"""open_output.py - open an mpm run in ParaView: particles as shaded spheres coloured by speed.

Loads OUTDIR/frames.pvd (the index of the run's frame_NNNN.vtu files), shows every particle
as a Point Gaussian sphere of radius half the particle spacing, colours it by the
magnitude of `velocity` (or another point array) over a range rescaled over all frames, looks
at the particles from the front, a little above and to the side (y is up, as gravity is -y in
the shipped scenes), and plays the frames once.

  pvpython tools/paraview/open_output.py OUTDIR [--field NAME] [--radius R]
                                                [--save-animation FILE.png|FILE.avi]
  MPM_OUTDIR=OUTDIR paraview --script=tools/paraview/open_output.py     (in the GUI)

--field    velocity (default, coloured by magnitude), J, stress, plastic, material, body, ...
--radius   sphere radius in metres (default: half the particle spacing, from `volume`)
--save-animation
           write the animation instead of opening a window (FILE.png gives FILE.NNNN.png);
           works under pvbatch too.

Written against the paraview.simple API of ParaView 5.9 to 5.12 with calls that its Python
trace itself records; the project's tests cannot run it (no ParaView there).
"""
import argparse
import os
import sys

from paraview.simple import (ColorBy, GetActiveCamera, GetAnimationScene,
                             GetColorTransferFunction, GetActiveViewOrCreate, Interact,
                             PVDReader, Render, SaveAnimation, Show)


def parse_args():
    """Options from the command line under pvpython/pvbatch; from $MPM_OUTDIR in the GUI."""
    cli = bool(sys.argv) and os.path.basename(sys.argv[0]) == "open_output.py"
    ap = argparse.ArgumentParser(description="open an mpm run in ParaView")
    ap.add_argument("outdir", nargs="?", default=os.environ.get("MPM_OUTDIR"),
                    help="the run's output directory (holds frames.pvd); default $MPM_OUTDIR")
    ap.add_argument("--field", default="velocity", help="point array to colour by")
    ap.add_argument("--radius", type=float, default=None, help="sphere radius (m)")
    ap.add_argument("--save-animation", metavar="FILE", default=None,
                    help="save the animation to FILE instead of opening a window")
    args = ap.parse_args(sys.argv[1:] if cli else [])
    if not args.outdir:
        ap.error("give the output directory (or set MPM_OUTDIR)")
    args.interactive = cli and not args.save_animation
    return args


def main():
    args = parse_args()
    pvd = os.path.join(args.outdir, "frames.pvd")
    if not os.path.isfile(pvd):
        sys.exit("open_output.py: %s not found; run `mpm run SCENE -o %s` first"
                 % (pvd, args.outdir))

    reader = PVDReader(FileName=pvd)
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    scene.PlayMode = "Snap To TimeSteps"

    view = GetActiveViewOrCreate("RenderView")
    display = Show(reader, view)

    # sphere radius: half the particle spacing, the cube root of the largest particle volume
    # of the first frame (volume = V0 J; J = 1 at frame 0)
    info = reader.GetDataInformation()
    b = info.GetBounds()
    ext = [max(b[2 * d + 1] - b[2 * d], 1e-9) for d in range(3)]
    if args.radius:
        radius = args.radius
    elif "volume" in reader.PointData.keys():
        radius = 0.5 * reader.PointData["volume"].GetRange()[1] ** (1.0 / 3.0)
    else:
        n = max(info.GetNumberOfPoints(), 1)
        radius = 0.5 * (ext[0] * ext[1] * ext[2] / n) ** (1.0 / 3.0)
    display.SetRepresentationType("Point Gaussian")
    display.GaussianRadius = radius
    display.ShaderPreset = "Sphere"

    # colour: velocity magnitude (or a scalar array), one fixed range over the whole run
    if args.field == "velocity":
        ColorBy(display, ("POINTS", "velocity", "Magnitude"))
    else:
        ColorBy(display, ("POINTS", args.field))
    lut = GetColorTransferFunction(args.field)
    lut.ApplyPreset("Viridis (matplotlib)", True)
    display.RescaleTransferFunctionToDataRangeOverTime()
    lut.AutomaticRescaleRangeMode = "Never"
    display.SetScalarBarVisibility(view, True)

    # camera: look at the particles from the front (+z), raised and turned a little, y up
    center = [0.5 * (b[2 * d] + b[2 * d + 1]) for d in range(3)]
    view.CameraFocalPoint = center
    view.CameraPosition = [center[0], center[1], center[2] + 3.0 * max(ext)]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    camera = GetActiveCamera()
    camera.Elevation(20.0)
    camera.Azimuth(25.0)
    view.ResetCamera()
    view.OrientationAxesVisibility = 1

    if args.save_animation:
        SaveAnimation(args.save_animation, view, ImageResolution=[1280, 720])
        return
    Render(view)
    if args.interactive:  # pvpython: play once, then leave the window to the user
        scene.Play()
        Interact(view)
    # in the GUI the view is shown and its own animation controls take over


main()
