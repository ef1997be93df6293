#!/usr/bin/python3
"""Pictures of the damage field of a cupid dynamic fracture run (examples/notched_plate).

    /usr/bin/python3 examples/notched_plate/render_damage.py [RUN_DIR] [-o DIR] [--prefix NAME]
        [--backend auto|opengl|software] [--range LO HI] [--warp FACTOR]

RUN_DIR (default out/notched_plate) holds the VTU series of the run: model.pvd and its
pd_<step>.vtu files (output.vtu: true), read with VTK. Writes into DIR (default RUN_DIR):
  NAME_mid.png    the frame where the crack is half way (its tip half way from where it started
                  to the farthest point it reaches),
  NAME_end.png    the last frame,
  NAME_strip.png  four frames side by side: the first with a broken bond, half way, the crack
                  through (the tip at its farthest), the end.
NAME is damage_field unless --prefix says otherwise. Each picture is the plate seen along -z
(its top face, parallel projection), every node drawn as a cell of the grid (a square of side h) coloured
by `damage` (a blue-to-red rainbow over --range, default 0..1), with a scalar bar titled
"damage" and the step and time in the title, as ParaView shows the same files (Glyph or Point
Gaussian, view +Z). --warp F draws the nodes at x + F u (ParaView's Warp By Vector), which makes
the crack opening visible (the grips move by 0.0125 mm); the default is 0, the reference grid.

Backends: `opengl` renders with VTK off screen (vtkRenderWindow, SetOffScreenRendering(1)); it
needs an X display (Debian's VTK 9 has no OSMesa or EGL window), e.g. `xvfb-run -a`. `software`
needs no display: numpy rasterises the squares, VTK's FreeType text renderer (no OpenGL)
writes the labels, and a small zlib writer stores the PNG. `auto` (the default) tries opengl in
a child process (a VTK build without a display aborts instead of raising) and falls back to
software; the line printed at the end names the backend used.

The crack tip of a frame is the largest reference x among the nodes that lost a bond to
breaking (damage above its value in the first frame, so the pre-crack does not count) within 4
grid spacings of the crack plane (the mean y of the first nodes to lose a bond); the script
prints it per picture.
"""
import argparse
import colorsys
import os
import re
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET
import zlib

import numpy as np
import vtk
from vtk.util import numpy_support as nps


# ---------------------------------------------------------------------------- reading

def frames_of(run):
    """[(step, t, path)] of the VTU series: model.pvd, else the pd_<step>.vtu files."""
    pvd = os.path.join(run, "model.pvd")
    out = []
    if os.path.exists(pvd):
        for ds in ET.parse(pvd).getroot().iter("DataSet"):
            f = ds.get("file")
            m = re.search(r"_(\d+)\.vtu$", f)
            if m and os.path.basename(f).startswith("pd"):
                out.append((int(m.group(1)), float(ds.get("timestep")), os.path.join(run, f)))
    else:
        for f in sorted(os.listdir(run)):
            m = re.fullmatch(r"pd_(\d+)\.vtu", f)
            if m:
                out.append((int(m.group(1)), float("nan"), os.path.join(run, f)))
    if not out:
        sys.exit("render_damage.py: no VTU series (model.pvd or pd_<step>.vtu) in %s; "
                 "run the model with output.vtu: true" % run)
    return sorted(out)


def read_vtu(path):
    r = vtk.vtkXMLUnstructuredGridReader()
    r.SetFileName(path)
    r.Update()
    g = r.GetOutput()
    pd = g.GetPointData()
    if pd.GetArray("damage") is None:
        sys.exit("render_damage.py: %s has no 'damage' point array (a model without "
                 "peridynamics.fracture?)" % path)
    x = nps.vtk_to_numpy(g.GetPoints().GetData()).astype(float)
    d = nps.vtk_to_numpy(pd.GetArray("damage")).astype(float)
    u = pd.GetArray("displacement")
    u = nps.vtk_to_numpy(u).astype(float) if u is not None else np.zeros_like(x)
    return x, d, u


# ---------------------------------------------------------------------------- colours

def colour_table(n=256):
    """ParaView's 'Blue to Red Rainbow': HSV hue 2/3 (blue) to 0 (red), full saturation."""
    return np.array([colorsys.hsv_to_rgb(2.0 / 3.0 * (1.0 - k / (n - 1.0)), 1.0, 1.0)
                     for k in range(n)])


def colours(values, lo, hi, table):
    s = np.clip((values - lo) / (hi - lo), 0.0, 1.0)
    return table[np.rint(s * (len(table) - 1)).astype(int)]


def label(v):
    return ("%.2f" % v).rstrip("0").rstrip(".") if v != 0 else "0"


def title_of(title, step, t):
    if t == t:  # not NaN
        return "%s: step %d, t = %.2f us" % (title, step, t * 1e6)
    return "%s: step %d" % (title, step)


# ---------------------------------------------------------------------------- opengl backend

def render_opengl(panels, lo, hi, table, h, size, path, suptitle):
    """panels: [(points, damage, title)]; one viewport each, side by side."""
    rw = vtk.vtkRenderWindow()
    rw.SetOffScreenRendering(1)
    rw.SetSize(*size)
    lut = vtk.vtkLookupTable()
    lut.SetNumberOfTableValues(len(table))
    for k, c in enumerate(table):
        lut.SetTableValue(k, c[0], c[1], c[2], 1.0)
    lut.SetRange(lo, hi)
    lut.Build()
    n = len(panels)
    bar_w = 0.16 if n == 1 else 0.07   # the scalar bar's share of the width
    for k, (pts, dam, title) in enumerate(panels):
        ren = vtk.vtkRenderer()
        ren.SetBackground(1, 1, 1)
        ren.SetViewport((1 - bar_w) * k / n, 0.0, (1 - bar_w) * (k + 1) / n, 0.92 if suptitle else 1.0)
        rw.AddRenderer(ren)
        poly = vtk.vtkPolyData()
        p = vtk.vtkPoints()
        p.SetData(nps.numpy_to_vtk(np.ascontiguousarray(pts), deep=1))
        poly.SetPoints(p)
        arr = nps.numpy_to_vtk(np.ascontiguousarray(dam), deep=1)
        arr.SetName("damage")
        poly.GetPointData().SetScalars(arr)
        cube = vtk.vtkCubeSource()
        cube.SetXLength(h)
        cube.SetYLength(h)
        cube.SetZLength(h)
        glyph = vtk.vtkGlyph3D()
        glyph.SetSourceConnection(cube.GetOutputPort())
        glyph.SetInputData(poly)
        glyph.SetScaleModeToDataScalingOff()
        glyph.SetColorModeToColorByScalar()
        mapper = vtk.vtkPolyDataMapper()
        mapper.SetInputConnection(glyph.GetOutputPort())
        mapper.SetLookupTable(lut)
        mapper.SetScalarRange(lo, hi)
        mapper.SetScalarModeToUsePointData()
        actor = vtk.vtkActor()
        actor.SetMapper(mapper)
        actor.GetProperty().SetAmbient(1.0)   # flat colours: the value, not the lighting
        actor.GetProperty().SetDiffuse(0.0)
        ren.AddActor(actor)
        cam = ren.GetActiveCamera()
        cam.ParallelProjectionOn()
        c = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
        cam.SetFocalPoint(*c)
        cam.SetPosition(c[0], c[1], c[2] + 100.0)
        cam.SetViewUp(0, 1, 0)
        ren.ResetCamera()
        ext = pts.max(axis=0) - pts.min(axis=0) + h
        vx0, vy0, vx1, vy1 = ren.GetViewport()
        aspect = (vx1 - vx0) * size[0] / ((vy1 - vy0) * size[1])
        cam.SetParallelScale(0.56 * max(ext[1], ext[0] / aspect) + (1.2 if title else 0))
        if title:
            txt = vtk.vtkTextActor()
            txt.SetInput(title)
            tp = txt.GetTextProperty()
            tp.SetColor(0, 0, 0)
            # shrink a long title to the panel (a character is about 0.55 font sizes wide)
            width = (vx1 - vx0) * size[0] - 10
            tp.SetFontSize(int(min(16 if n > 1 else 18, width / (0.55 * len(title)))))
            tp.SetJustificationToCentered()
            tp.SetVerticalJustificationToTop()
            txt.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
            txt.SetPosition(0.5, 0.985)
            ren.AddViewProp(txt)
    over = vtk.vtkRenderer()   # the scalar bar and the overall title
    over.SetBackground(1, 1, 1)
    over.SetViewport(1 - bar_w, 0.0, 1.0, 0.92 if suptitle else 1.0)
    rw.AddRenderer(over)
    bar = vtk.vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetTitle("damage")
    bar.SetNumberOfLabels(6)
    bar.SetLabelFormat("%.1f")
    bar.UnconstrainedFontSizeOn()
    for tp in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        tp.SetColor(0, 0, 0)
        tp.ItalicOff()
        tp.BoldOff()
        tp.ShadowOff()
    bar.GetTitleTextProperty().SetFontSize(18)
    bar.GetLabelTextProperty().SetFontSize(15)
    bar.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    bar.SetVerticalTitleSeparation(8)
    bar.SetPosition(0.12, 0.1)
    bar.SetWidth(0.75)
    bar.SetHeight(0.74)
    bar.SetBarRatio(0.3)
    over.AddViewProp(bar)
    if suptitle:
        top = vtk.vtkRenderer()
        top.SetBackground(1, 1, 1)
        top.SetViewport(0.0, 0.92, 1.0, 1.0)
        rw.AddRenderer(top)
        txt = vtk.vtkTextActor()
        txt.SetInput(suptitle)
        tp = txt.GetTextProperty()
        tp.SetColor(0, 0, 0)
        tp.SetFontSize(20)
        tp.SetJustificationToCentered()
        tp.SetVerticalJustificationToCentered()
        txt.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        txt.SetPosition(0.5, 0.5)
        top.AddViewProp(txt)
    rw.Render()
    w2i = vtk.vtkWindowToImageFilter()
    w2i.SetInput(rw)
    w2i.ReadFrontBufferOff()
    w2i.Update()
    png = vtk.vtkPNGWriter()
    png.SetFileName(path)
    png.SetInputConnection(w2i.GetOutputPort())
    png.Write()
    rw.Finalize()


# ---------------------------------------------------------------------------- software backend

def text_image(s, size, bold=False):
    """An RGBA uint8 array (rows top down) of the string in black, by VTK's FreeType renderer
    (no OpenGL); None if this VTK has no FreeType."""
    tr = vtk.vtkTextRenderer()
    tp = vtk.vtkTextProperty()
    tp.SetFontSize(size)
    tp.SetColor(0, 0, 0)
    tp.SetBold(bool(bold))
    img = vtk.vtkImageData()
    dims = [0, 0]
    if not tr.RenderString(tp, s, img, dims, 72):
        return None
    nx, ny, _ = img.GetDimensions()
    a = nps.vtk_to_numpy(img.GetPointData().GetScalars()).reshape(ny, nx, -1)
    a = a[::-1]                          # VTK rows run bottom up
    return a[ny - dims[1]:, :dims[0]] if dims[0] > 0 and dims[1] > 0 else a


def blit_text(canvas, s, size, cx, y, bold=False, anchor="centre", width=None):
    t = text_image(s, size, bold)
    while t is not None and width and t.shape[1] > width and size > 8:
        size -= 1                        # shrink a long title to the room it has
        t = text_image(s, size, bold)
    if t is None:
        return
    th, tw = t.shape[:2]
    x0 = int(round(cx - tw / 2)) if anchor == "centre" else int(round(cx))
    y0 = int(round(y - th / 2))
    H, W = canvas.shape[:2]
    xa, ya = max(x0, 0), max(y0, 0)
    xb, yb = min(x0 + tw, W), min(y0 + th, H)
    if xa >= xb or ya >= yb:
        return
    sub = t[ya - y0:yb - y0, xa - x0:xb - x0].astype(float)
    alpha = sub[..., 3:4] / 255.0
    canvas[ya:yb, xa:xb] = (1 - alpha) * canvas[ya:yb, xa:xb] + alpha * sub[..., :3] / 255.0


def render_software(panels, lo, hi, table, h, size, path, suptitle):
    W, H = size
    canvas = np.ones((H, W, 3))
    n = len(panels)
    bar_w = int((0.16 if n == 1 else 0.07) * W)
    top = int(0.08 * H) if suptitle else 0
    pw = (W - bar_w) // n
    for k, (pts, dam, title) in enumerate(panels):
        title_h = 30 if title else 0
        z = pts[:, 2]
        face = z >= z.max() - 0.5 * h         # the top layer: what a view along -z shows
        p, d = pts[face], dam[face]
        lo_xy = p[:, :2].min(axis=0) - 0.5 * h
        ext = p[:, :2].max(axis=0) + 0.5 * h - lo_xy
        avail_w, avail_h = pw - 20, H - top - title_h - 20
        s = min(avail_w / ext[0], avail_h / ext[1])    # pixels per length unit
        ox = k * pw + (pw - s * ext[0]) / 2
        oy = top + title_h + (H - top - title_h - s * ext[1]) / 2
        col = colours(d, lo, hi, table)
        # a cell of the grid per node, its edges rounded the same way for both neighbours so
        # that the cells tile the plate; drawn in order of increasing damage, so that the
        # damaged ones stay on top where warped cells overlap
        for j in np.argsort(d, kind="stable"):
            ex = ox + (p[j, 0] - lo_xy[0] + np.array([-0.5, 0.5]) * h) * s
            ey = oy + (lo_xy[1] + ext[1] - p[j, 1] + np.array([-0.5, 0.5]) * h) * s   # y up
            x0, x1 = (int(v) for v in np.rint(ex))
            y0, y1 = (int(v) for v in np.rint(ey))
            canvas[max(y0, 0):max(y1, 0), max(x0, 0):max(x1, 0)] = col[j]
        if title:
            blit_text(canvas, title, 16 if n > 1 else 18, k * pw + pw / 2, top + 16, width=pw - 10)
    # scalar bar
    bx0 = W - bar_w + int(0.12 * bar_w)
    bw = max(int(0.22 * bar_w), 12) if n == 1 else max(int(0.25 * bar_w), 12)
    by0, by1 = top + int(0.16 * (H - top)), top + int(0.88 * (H - top))
    for y in range(by0, by1):
        v = 1.0 - (y - by0) / max(by1 - by0 - 1, 1)
        canvas[y, bx0:bx0 + bw] = table[int(round(v * (len(table) - 1)))]
    canvas[by0:by1, bx0] = canvas[by0:by1, bx0 + bw - 1] = 0
    canvas[by0, bx0:bx0 + bw] = canvas[by1 - 1, bx0:bx0 + bw] = 0
    blit_text(canvas, "damage", 18, bx0 + bw / 2, by0 - 22, anchor="centre")
    for v in np.linspace(lo, hi, 6):
        y = by1 - 1 - (v - lo) / (hi - lo) * (by1 - by0 - 1)
        canvas[int(round(y)), bx0 + bw:bx0 + bw + 5] = 0
        blit_text(canvas, "%.1f" % v, 15, bx0 + bw + 8, y, anchor="left")
    if suptitle:
        blit_text(canvas, suptitle, 20, W / 2, top / 2)
    write_png(path, (np.clip(canvas, 0, 1) * 255 + 0.5).astype(np.uint8))


def write_png(path, rgb):
    """An 8-bit RGB PNG from an (H, W, 3) uint8 array: zlib and struct only."""
    H, W, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(H))

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))
    with open(path + ".tmp", "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    os.replace(path + ".tmp", path)


# ---------------------------------------------------------------------------- main

PROBE = r"""
import vtk
rw = vtk.vtkRenderWindow(); rw.SetOffScreenRendering(1); rw.SetSize(32, 32)
r = vtk.vtkRenderer(); rw.AddRenderer(r); rw.Render()
w = vtk.vtkWindowToImageFilter(); w.SetInput(rw); w.Update()
assert w.GetOutput().GetDimensions()[0] == 32
print("ok")
"""


def opengl_works():
    try:
        p = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60)
        return p.returncode == 0 and p.stdout.strip() == "ok"
    except (OSError, subprocess.TimeoutExpired):
        return False


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", nargs="?", default="out/notched_plate", help="the run's output directory")
    ap.add_argument("-o", "--out", help="where to write the pictures (default: the run directory)")
    ap.add_argument("--prefix", default="damage_field", help="file name stem of the pictures")
    ap.add_argument("--backend", choices=("auto", "opengl", "software"), default="auto")
    ap.add_argument("--range", nargs=2, type=float, default=(0.0, 1.0), metavar=("LO", "HI"))
    ap.add_argument("--warp", type=float, default=0.0, help="draw nodes at x + WARP u")
    ap.add_argument("--title", help="picture title (default: the model's title in summary.json)")
    a = ap.parse_args()
    out = a.out or a.run
    os.makedirs(out, exist_ok=True)
    lo, hi = a.range
    if not hi > lo:
        sys.exit("render_damage.py: --range needs LO < HI")
    title = a.title
    if title is None:
        try:
            import json
            title = json.load(open(os.path.join(a.run, "summary.json"))).get("title") or "cupid"
        except (OSError, ValueError):
            title = "cupid"

    frames = frames_of(a.run)
    data = [read_vtu(f) for _, _, f in frames]
    x0, d0, _ = data[0]
    xs = np.unique(np.round(x0[:, 0], 9))
    h = float(np.min(np.diff(xs))) if len(xs) > 1 else 1.0   # the grid spacing
    # the crack band: within 4 spacings of the mean y of the first nodes to lose a bond (away
    # from it, a few nodes at the grip edges lose a bond or two: they are not the crack)
    broken = [d > d0 + 1e-12 for x, d, _ in data]
    started = [i for i, b in enumerate(broken) if b.any()]
    yc = float(x0[broken[started[0]], 1].mean()) if started else 0.0
    tips = []
    for (x, d, _), b in zip(data, broken):
        b = b & (np.abs(x0[:, 1] - yc) <= 4 * h)
        tips.append(float(x0[b, 0].max()) if b.any() else float("nan"))
    tips = np.array(tips)
    have = np.flatnonzero(~np.isnan(tips))
    last = len(frames) - 1
    if len(have) == 0:
        print("render_damage.py: no bond broke in this run (only the pre-crack's damage)")
        first = mid = through = last
    else:
        first = int(have[0])
        tmax = np.nanmax(tips)
        half = tips[first] + 0.5 * (tmax - tips[first])
        mid = int(next(i for i in have if tips[i] >= half))
        through = int(next(i for i in have if tips[i] >= tmax))

    backend = a.backend
    if backend == "auto":
        backend = "opengl" if opengl_works() else "software"
    draw = render_opengl if backend == "opengl" else render_software
    table = colour_table()

    def panel(i, with_title=True):
        x, d, u = data[i]
        step, t, _ = frames[i]
        return (x + a.warp * u, d, title_of(title, step, t) if with_title else None)

    def short(i, what):
        step, t, _ = frames[i]
        tt = "t = %.1f us" % (t * 1e6) if t == t else ""
        return "%s: step %d, %s" % (what, step, tt)

    written = []
    for name, i in (("mid", mid), ("end", last)):
        path = os.path.join(out, "%s_%s.png" % (a.prefix, name))
        draw([panel(i)], lo, hi, table, h, (760, 640), path, None)
        written.append((path, i))
    strip = [(first, "first break"), (mid, "half way"), (through, "through"), (last, "end")]
    path = os.path.join(out, "%s_strip.png" % a.prefix)
    panels = []
    for i, what in strip:
        x, d, u = data[i]
        panels.append((x + a.warp * u, d, short(i, what)))
    draw(panels, lo, hi, table, h, (1600, 480), path, title)
    written.append((path, None))
    for path, i in written:
        if i is None:
            desc = ", ".join("step %d (tip x = %s)" % (frames[j][0], "%.1f" % tips[j] if tips[j] == tips[j] else "-")
                             for j, _ in strip)
        else:
            desc = "step %d, t = %.4g s, crack tip x = %s, max damage %.3f" % (
                frames[i][0], frames[i][1], "%.1f" % tips[i] if tips[i] == tips[i] else "-", data[i][1].max())
        print("%s (%d KB): %s" % (path, (os.path.getsize(path) + 512) // 1024, desc))
    print("backend: %s (%d frames read from %s)" % (
        "VTK OpenGL, off screen" if backend == "opengl" else "software (numpy squares, VTK FreeType text, zlib PNG)",
        len(frames), a.run))


if __name__ == "__main__":
    main()
