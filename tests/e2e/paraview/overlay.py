"""Overlay check (issue 21): a scan's labels, its level set and the carved packing, loaded together,
occupy the same place in metres.

    pvpython overlay.py FOLDER [--picture overlay.png]   # ParaView: reads the XDMF sidecars
    python3  overlay.py FOLDER --h5py # the same bounds from the HDF5 files (h5py, numpy)

With ParaView the boxes come from its XDMF reader and threshold filter, as a user opening the
files sees them; --picture also renders the three together (needs an OpenGL context: Debian 12's
ParaView 5.11 renders only through GLX, so CI, headless, checks the boxes without a picture).
Without ParaView, or with --h5py, the boxes come from the HDF5 files.

FOLDER holds labels.h5 (+ labels.xdmf), pores.vdb and carved.h5 (+ carved.xdmf), as written by
tomodem-segment and tomodem-carve (tests/e2e/paraview/overlay_run.sh makes them). The level set is
read with pyopenvdb (ParaView 5.11 has no OpenVDB reader) in its own unit, from its metadata.

Checks, each within one voxel (the largest spacing), on every face:
  1. the labels' box (voxel faces) equals the carved packing's cell box;
  2. the level set's interior (phi < 0) has the box of the macropore voxels (label 2);
  3. every particle centre of the carved packing lies inside the labels' box.
Exit 0 when all hold, 1 when one fails, 77 (skipped) when neither ParaView nor h5py is there.
"""
import json
import math
import os
import sys

SKIP = 77


def box_text(b):
    return "[" + ", ".join("%.6g..%.6g" % (b[2 * k], b[2 * k + 1]) for k in range(3)) + "] m"


def worst_gap(a, b):
    return max(abs(a[i] - b[i]) for i in range(6))


def length_unit(attrs, what):
    """Metres per unit of a file's root attribute `units` (absent: metres, the old convention)."""
    u = attrs.get("units", "m")
    u = u.decode() if isinstance(u, bytes) else str(u)
    scale = {"m": 1.0, "mm": 1e-3, "um": 1e-6, "nm": 1e-9}.get(u)
    if scale is None:
        raise SystemExit("%s: unknown length unit %r" % (what, u))
    return scale


def level_set_interior_box(path):
    """Box of the voxels with phi < 0 (faces, in metres), from the grid's own unit metadata."""
    try:
        import numpy as np
        import pyopenvdb as vdb
    except ImportError:
        return None
    grid = vdb.read(path, "macropores")
    meta = grid.metadata
    if "metres_per_unit" in meta:
        unit = float(meta["metres_per_unit"])
    else:
        unit = {"m": 1.0, "mm": 1e-3, "um": 1e-6}[meta.get("units", "m")]
    lo, hi = grid.evalActiveVoxelBoundingBox()
    shape = tuple(hi[k] - lo[k] + 1 for k in range(3))
    dense = np.full(shape, grid.background, dtype=np.float32)
    grid.copyToArray(dense, ijk=lo)
    inside = np.argwhere(dense < 0)
    if inside.size == 0:
        raise SystemExit(path + ": the level set has no interior")
    imin = inside.min(axis=0) + np.array(lo)
    imax = inside.max(axis=0) + np.array(lo)
    a = grid.transform.indexToWorld(tuple(float(x) - 0.5 for x in imin))
    b = grid.transform.indexToWorld(tuple(float(x) + 0.5 for x in imax))
    out = []
    for k in range(3):
        out += [min(a[k], b[k]) * unit, max(a[k], b[k]) * unit]
    return out


def from_hdf5(folder):
    """Labels box, macropore box, voxel, cell box and particle centres' box from the HDF5 files."""
    import h5py
    import numpy as np
    with h5py.File(os.path.join(folder, "labels.h5"), "r") as f:
        u = length_unit(f.attrs, "labels.h5")
        lab = f["/labels"]
        sp = np.asarray(lab.attrs["spacing"], dtype=float) * u
        org = np.asarray(lab.attrs["origin"], dtype=float) * u
        nz, ny, nx = lab.shape
        n = np.array([nx, ny, nz])
        scan = sum(([org[k] - sp[k] / 2, org[k] + (n[k] - 0.5) * sp[k]] for k in range(3)), [])
        idx = np.argwhere(lab[...] == 2)  # (z, y, x)
        if idx.size == 0:
            raise SystemExit("labels.h5: no macropore voxel (label 2)")
        lo, hi = idx.min(axis=0)[::-1], idx.max(axis=0)[::-1]
        macro = sum(([org[k] + (lo[k] - 0.5) * sp[k], org[k] + (hi[k] + 0.5) * sp[k]] for k in range(3)), [])
    with h5py.File(os.path.join(folder, "carved.h5"), "r") as f:
        u = length_unit(f.attrs, "carved.h5")
        o = np.asarray(f["/cell/origin"][...], dtype=float) * u
        h = np.asarray(f["/cell/h"][...], dtype=float) * u
        corners = np.array([o + h @ np.array(c) for c in np.ndindex(2, 2, 2)])
        cell = sum(([corners[:, k].min(), corners[:, k].max()] for k in range(3)), [])
        x = np.asarray(f["/particles/position"][...], dtype=float) * u
        centres = sum(([x[:, k].min(), x[:, k].max()] for k in range(3)), []) if len(x) else None
    return scan, macro, float(sp.max()), cell, centres


def from_paraview(folder, out_png=None):
    """The same boxes as ParaView sees them through the XDMF sidecars; a picture when asked."""
    import paraview.simple as pv
    labels = pv.XDMFReader(FileNames=[os.path.join(folder, "labels.xdmf")])
    labels.UpdatePipeline()
    scan = list(labels.GetDataInformation().GetBounds())
    cells = labels.GetDataInformation().GetNumberOfCells()
    macro_f = pv.Threshold(Input=labels, Scalars=["CELLS", "labels"])
    # ParaView 5.10+ names the range LowerThreshold/UpperThreshold; 5.9 and older ThresholdRange.
    if macro_f.GetProperty("LowerThreshold") is not None:
        macro_f.LowerThreshold, macro_f.UpperThreshold = 2, 2
    else:
        macro_f.ThresholdRange = [2, 2]
    macro_f.UpdatePipeline()
    macro = list(macro_f.GetDataInformation().GetBounds())
    packing = pv.XDMFReader(FileNames=[os.path.join(folder, "carved.xdmf")])
    packing.UpdatePipeline()
    centres = list(packing.GetDataInformation().GetBounds())
    voxel = max((scan[2 * k + 1] - scan[2 * k]) for k in range(3)) / max(1.0, round(cells ** (1.0 / 3.0)))
    if out_png:
        save_picture(pv, labels, macro_f, packing, out_png)
    return scan, macro, voxel, centres


def save_picture(pv, labels, macro_f, packing, out_png):
    """The macropores (translucent), the scan's outline and the particles in one view."""
    view = pv.CreateRenderView()
    view.ViewSize = [800, 600]
    d = pv.Show(macro_f, view)
    d.Opacity = 0.4
    o = pv.Show(labels, view)
    o.SetRepresentationType("Outline")
    g = pv.Show(packing, view)
    g.SetRepresentationType("Point Gaussian")
    g.ScaleByArray = 1
    # ParaView 5.11 names the scale array property SetScaleArray (older versions ScaleArray).
    for prop in ("SetScaleArray", "ScaleArray"):
        if g.GetProperty(prop) is not None:
            g.SetPropertyWithName(prop, ["POINTS", "radius"])
            break
    g.UseScaleFunction = 0
    g.GaussianRadius = 1.0
    pv.ResetCamera(view)
    pv.SaveScreenshot(out_png, view)


def main():
    args = sys.argv[1:]
    picture, force_h5py = None, "--h5py" in args
    if "--picture" in args:
        i = args.index("--picture")
        if i + 1 >= len(args):
            print(__doc__)
            return 2
        picture = args[i + 1]
        del args[i:i + 2]
    args = [a for a in args if a != "--h5py"]
    if len(args) != 1:
        print(__doc__)
        return 2
    folder = args[0]
    mode = None
    try:
        if force_h5py:
            raise ImportError("--h5py")
        import paraview.simple  # noqa: F401
        mode = "paraview"
    except ImportError:
        try:
            import h5py  # noqa: F401
            import numpy  # noqa: F401
            mode = "h5py"
        except ImportError:
            print("overlay: skipped: neither ParaView (pvpython) nor h5py/numpy is installed")
            return SKIP
    scan, macro, voxel, cell, centres = from_hdf5(folder) if mode == "h5py" else (None,) * 5
    if mode == "paraview":
        scan, macro, voxel_pv, centres = from_paraview(folder, picture)
        cell = None
        try:  # the cell box is not in the XDMF; take it from the HDF5 when h5py is there
            _, _, voxel, cell, _ = from_hdf5(folder)
        except ImportError:
            voxel = voxel_pv
    ls = level_set_interior_box(os.path.join(folder, "pores.vdb"))
    report = {"mode": mode, "voxel_m": voxel, "labels_box_m": scan, "macropore_box_m": macro,
              "cell_box_m": cell, "particle_centres_box_m": centres, "level_set_interior_box_m": ls}
    failures = []
    if cell is not None:
        report["labels_vs_cell_m"] = worst_gap(scan, cell)
        if report["labels_vs_cell_m"] > voxel:
            failures.append("labels %s and packing cell %s differ by more than a voxel" % (box_text(scan), box_text(cell)))
    if ls is not None:
        report["level_set_vs_macropores_m"] = worst_gap(ls, macro)
        if report["level_set_vs_macropores_m"] > voxel:
            failures.append("level set interior %s and macropore voxels %s differ by more than a voxel"
                            % (box_text(ls), box_text(macro)))
    else:
        report["level_set_vs_macropores_m"] = None
        print("overlay: pyopenvdb not installed: the level set is not checked")
    if centres is not None:
        out = max(max(scan[2 * k] - centres[2 * k], centres[2 * k + 1] - scan[2 * k + 1]) for k in range(3))
        report["centres_outside_labels_m"] = max(0.0, out)
        if out > voxel:
            failures.append("particle centres %s leave the labels' box %s" % (box_text(centres), box_text(scan)))
    print(json.dumps(report, indent=2))
    for f in failures:
        print("overlay: FAIL: " + f)
    if not math.isfinite(voxel) or voxel <= 0:
        failures.append("no voxel size")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
