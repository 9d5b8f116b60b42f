"""Map pictures of livo-report (scripts/livo-report imports this file from its own folder): map.pcd read
with numpy (DATA ascii, binary, binary_compressed), drawn by a small parallel-projection rasteriser with a
depth buffer (no display, no OpenGL), from above and obliquely, with the trajectory drawn over it.
Errors in the file raise PcdError naming it."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


class PcdError(ValueError):
    pass


def fail(msg):
    raise PcdError(msg)


def read_pcd(path):
    """xyz (n x 3) and rgb (n x 3, uint8, None without colour) of a PCD file: DATA ascii, binary or
    binary_compressed (LZF), fields x y z and optionally rgb / rgba (packed as PCL writes them)."""
    with open(path, "rb") as f:
        raw = f.read()
    header, pos = {}, 0
    while True:
        end = raw.find(b"\n", pos)
        if end < 0:
            fail(f"{path}: PCD header without a DATA line")
        line = raw[pos:end].decode("ascii", "replace").strip()
        pos = end + 1
        if not line or line.startswith("#"):
            continue
        key, _, value = line.partition(" ")
        header[key.upper()] = value.split()
        if key.upper() == "DATA":
            break
    try:
        fields = header["FIELDS"]
        sizes = [int(v) for v in header["SIZE"]]
        types = header["TYPE"]
        counts = [int(v) for v in header.get("COUNT", ["1"] * len(fields))]
        n = int(header["POINTS"][0]) if "POINTS" in header else int(header["WIDTH"][0]) * int(header["HEIGHT"][0])
        data = header["DATA"][0]
    except (KeyError, ValueError, IndexError):
        fail(f"{path}: not a PCD file (header incomplete)")
    if not {"x", "y", "z"} <= set(fields):
        fail(f"{path}: PCD without x, y, z fields (has: {' '.join(fields)})")
    kinds = {("F", 4): "<f4", ("F", 8): "<f8", ("U", 1): "u1", ("U", 2): "<u2", ("U", 4): "<u4",
             ("I", 1): "i1", ("I", 2): "<i2", ("I", 4): "<i4"}
    try:
        dtype = np.dtype([(f, kinds[(t, s)], (c,)) if c > 1 else (f, kinds[(t, s)])
                          for f, s, t, c in zip(fields, sizes, types, counts)])
    except KeyError:
        fail(f"{path}: unsupported PCD field type")
    if data == "ascii":
        text = raw[pos:].decode("ascii", "replace").split()
        vals = np.array(text[: n * sum(counts)], dtype=float).reshape(n, sum(counts)) if n else np.zeros((0, 3))
        col = {f: i for i, f in enumerate(fields)}  # counts are 1 for the fields read here
        pts = np.zeros(n, dtype=dtype)
        for f in ("x", "y", "z"):
            pts[f] = vals[:, col[f]]
        for f in ("rgb", "rgba"):
            if f in col:
                pts[f] = vals[:, col[f]]  # a float rgb keeps its bits through float64 -> float32
    elif data == "binary":
        if len(raw) - pos < n * dtype.itemsize:
            fail(f"{path}: truncated ({len(raw) - pos} bytes of data for {n} points)")
        pts = np.frombuffer(raw, dtype=dtype, count=n, offset=pos)
    elif data == "binary_compressed":
        csize, usize = np.frombuffer(raw, "<u4", 2, pos)
        buf = lzf_decompress(raw[pos + 8: pos + 8 + int(csize)], int(usize), path)
        # Field after field (all x, then all y, ...).
        pts, off = np.zeros(n, dtype=dtype), 0
        for f in fields:
            pts[f] = np.frombuffer(buf, dtype[f].base, n * int(np.prod(dtype[f].shape, dtype=int)), off).reshape(pts[f].shape)
            off += dtype[f].itemsize * n
    else:
        fail(f"{path}: unknown PCD DATA '{data}'")
    xyz = np.stack([pts["x"], pts["y"], pts["z"]], axis=1).astype(float)
    rgb = None
    for f in ("rgb", "rgba"):
        if f in fields:
            packed = np.ascontiguousarray(pts[f]).view(np.uint32)
            rgb = np.stack([(packed >> 16) & 255, (packed >> 8) & 255, packed & 255], axis=1).astype(np.uint8)
    ok = np.isfinite(xyz).all(axis=1)
    return xyz[ok], (rgb[ok] if rgb is not None else None)


def lzf_decompress(src, size, path):
    """LZF (as PCL's binary_compressed uses it), in plain Python."""
    out, i = bytearray(), 0
    while i < len(src):
        ctrl = src[i]
        i += 1
        if ctrl < 32:  # literal run of ctrl + 1 bytes
            out += src[i: i + ctrl + 1]
            i += ctrl + 1
        else:  # back reference
            length = ctrl >> 5
            if length == 7:
                length += src[i]
                i += 1
            ref = len(out) - ((ctrl & 31) << 8) - src[i] - 1
            i += 1
            if ref < 0:
                fail(f"{path}: corrupt compressed PCD data")
            for k in range(length + 2):
                out.append(out[ref + k])
    if len(out) != size:
        fail(f"{path}: compressed PCD data of {len(out)} bytes, header says {size}")
    return bytes(out)


def rasterise(uv, depth, colours, res, splat, shape):
    """Parallel-projection rasteriser with a depth buffer: uv in metres on the picture plane (u right, v
    up, from the picture's lower left corner), depth larger = farther; each point a square of
    (2 splat + 1)^2 pixels. Returns an RGB float image (background NaN) and a mask."""
    h, w = shape
    cols = np.floor(uv[:, 0] / res).astype(np.int64)
    rows = (h - 1) - np.floor(uv[:, 1] / res).astype(np.int64)
    offs = [(dr, dc) for dr in range(-splat, splat + 1) for dc in range(-splat, splat + 1)]
    r = np.concatenate([rows + dr for dr, _ in offs])
    c = np.concatenate([cols + dc for _, dc in offs])
    d = np.tile(depth, len(offs))
    k = np.tile(np.arange(len(depth)), len(offs))
    inside = (r >= 0) & (r < h) & (c >= 0) & (c < w)
    r, c, d, k = r[inside], c[inside], d[inside], k[inside]
    pix = r * w + c
    order = np.lexsort((d, pix))  # per pixel, the nearest point first
    first = np.ones(len(order), dtype=bool)
    first[1:] = pix[order][1:] != pix[order][:-1]
    win = order[first]
    img = np.full((h, w, 3), np.nan)
    img[r[win], c[win]] = colours[k[win]]
    return img


def view_axes(elev_deg, azim_deg=45.0):
    """Parallel view from elev_deg above the horizon, looking towards azimuth azim_deg (from +x towards
    +y): the picture's right and up axes and the viewing direction d (into the scene)."""
    if elev_deg >= 90.0:
        return np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, -1.0])
    e, a = np.radians(elev_deg), np.radians(azim_deg)
    d = np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), -np.sin(e)])
    right = np.cross(d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    return right, np.cross(right, d), d


def map_pictures(xyz, rgb, traj, clip_m, camera_ran, voxel_m, out):
    """map_top.png and map_oblique.png: map.pcd by height and (camera_ran) by the camera's colour, with the
    trajectory over it; returns the file names written."""
    if clip_m > 0 and len(traj):
        keep = xyz[:, 2] <= traj[:, 2].max() + clip_m
        xyz, rgb = xyz[keep], (rgb[keep] if rgb is not None else None)
    if len(xyz) == 0:
        return []
    lo_z, hi_z = np.percentile(xyz[:, 2], [1, 99])
    t = np.clip((xyz[:, 2] - lo_z) / max(hi_z - lo_z, 1e-6), 0, 1)
    panels = [("coloured by height", plt.get_cmap("turbo")(0.12 + 0.83 * t)[:, :3])]  # turbo without its darkest ends
    if camera_ran and rgb is not None:
        panels.append(("coloured by the camera", rgb / 255.0))
    names = []
    for name, elev in (("top", 90.0), ("oblique", 35.0)):
        right, up, d = view_axes(elev)
        uv, depth = np.stack([xyz @ right, xyz @ up], axis=1), xyz @ d
        lo, hi = np.percentile(uv, 0.5, axis=0), np.percentile(uv, 99.5, axis=0)  # a few far points do not count
        span = np.maximum(hi - lo, 1.0)
        lo, hi = lo - 0.04 * span, hi + 0.04 * span
        res = max((hi - lo).max() / 900.0, 0.005)  # metres per pixel, about 900 pixels along the longer side
        shape = (int(np.ceil((hi[1] - lo[1]) / res)), int(np.ceil((hi[0] - lo[0]) / res)))
        splat = int(np.clip(np.ceil(0.6 * voxel_m / res), 0, 8))  # one voxel covers its pixels
        # Oblique: farther points darker (up to 35 %), a cue for depth without lighting.
        shade = 1.0 if elev >= 90.0 else 1.0 - 0.35 * (depth - depth.min()) / max(np.ptp(depth), 1e-6)
        tr = (np.stack([traj @ right, traj @ up], axis=1) - lo) / res if len(traj) else np.zeros((0, 2))
        fig, axes = plt.subplots(1, len(panels), figsize=(6.2 * len(panels), 5.4), squeeze=False)
        for ax, (title, colours) in zip(axes[0], panels):
            img = rasterise(uv - lo, depth, colours * np.reshape(shade, (-1, 1)), res, splat, shape)
            ax.imshow(np.where(np.isnan(img), 0.08, img), extent=(0, shape[1], 0, shape[0]), interpolation="nearest")
            if len(tr):
                ax.plot(tr[:, 0], tr[:, 1], "-", color="white", lw=3.0)
                ax.plot(tr[:, 0], tr[:, 1], "-", color="magenta", lw=1.5, label="trajectory")
                ax.plot(tr[0, 0], tr[0, 1], "o", color="lime", ms=5, label="start")
            if name == "top":  # scale bar
                x0, y0 = 0.04 * shape[1], 0.04 * shape[0]
                ax.plot([x0, x0 + 1.0 / res], [y0, y0], "w-", lw=2)
                ax.text(x0, y0 + 0.02 * shape[0], "1 m", color="white", fontsize=8)
            ax.set_title(title, fontsize=10)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.legend(loc="upper right", fontsize=7)
        what = "from above (x right, y up)" if name == "top" else "from 35 degrees above the horizon, looking north-east (+x +y)"
        cut = f"; points higher than the highest pose + {clip_m:g} m left out" if clip_m > 0 else ""
        fig.suptitle(f"map.pcd {what}{cut}", fontsize=10)
        fig.tight_layout()
        fig.savefig(os.path.join(out, f"map_{name}.png"), dpi=100)
        plt.close(fig)
        names.append(f"map_{name}.png")
    return names
