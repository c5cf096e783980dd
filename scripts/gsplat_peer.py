#!/usr/bin/env python3
"""Times gsplat's CUDA rasterizer on the scenes and cameras that `cargo bench --bench render --
--write-scenes DIR` wrote, so that cogeo and gsplat are compared on the same GPU, scene and camera.

    python3 scripts/gsplat_peer.py DIR [--frames 10] [--json OUT.json]

For every DIR/scene-<n>.ply and DIR/camera-<w>x<h>.json it prints the median forward time and the
median forward+backward time (CUDA events, after warm-up), and gsplat's intersection count, which
must be close to cogeo's for the same scene and camera (a check that both read the scene alike).
Needs torch and the `gsplat` package (its CUDA kernels compile on first use).
"""
import argparse
import glob
import json
import os
import re
import statistics

import numpy as np
import torch


def read_ply(path):
    """Binary little-endian INRIA PLY -> dict of float32 arrays (one per property)."""
    with open(path, "rb") as f:
        names, count = [], None
        while True:
            line = f.readline().decode("ascii").strip()
            if line.startswith("element vertex"):
                count = int(line.split()[2])
            elif line.startswith("property"):
                kind, name = line.split()[1:3]
                if kind != "float":
                    raise SystemExit(f"{path}: property {name} is {kind}, expected float")
                names.append(name)
            elif line == "end_header":
                break
        dtype = np.dtype([(n, "<f4") for n in names])
        data = np.frombuffer(f.read(count * dtype.itemsize), dtype=dtype, count=count)
    return data


def gaussians(path, device):
    d = read_ply(path)
    col = lambda *ns: torch.from_numpy(np.stack([d[n] for n in ns], axis=1).copy()).to(device)
    means = col("x", "y", "z")
    quats = col("rot_0", "rot_1", "rot_2", "rot_3")  # w x y z, normalised by gsplat
    scales = torch.exp(col("scale_0", "scale_1", "scale_2"))
    opacities = torch.sigmoid(torch.from_numpy(d["opacity"].copy()).to(device))
    rest = sorted((n for n in d.dtype.names if n.startswith("f_rest_")), key=lambda n: int(n[7:]))
    dc = col("f_dc_0", "f_dc_1", "f_dc_2")[:, None, :]
    k = len(rest) // 3
    sh = torch.cat([dc, col(*rest).reshape(-1, 3, k).transpose(1, 2)], dim=1).contiguous()
    degree = int(round((k + 1) ** 0.5)) - 1
    return means, quats, scales, opacities, sh, degree


def time_ms(fn, frames):
    for _ in range(3):
        fn()
    torch.cuda.synchronize()
    times = []
    for _ in range(frames):
        start, end = torch.cuda.Event(enable_timing=True), torch.cuda.Event(enable_timing=True)
        start.record()
        fn()
        end.record()
        torch.cuda.synchronize()
        times.append(start.elapsed_time(end))
    return statistics.median(times), min(times), max(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dir", help="folder written by the render bench's --write-scenes")
    ap.add_argument("--frames", type=int, default=10, help="timed frames per case (median reported)")
    ap.add_argument("--json", help="also write the rows here")
    args = ap.parse_args()
    from gsplat import rasterization  # noqa: E402  (compiles its kernels on first use)
    import gsplat

    dev = torch.device("cuda")
    print(f"gsplat {gsplat.__version__}, torch {torch.__version__}, {torch.cuda.get_device_name(0)}")
    rows = []
    scenes = sorted(glob.glob(os.path.join(args.dir, "scene-*.ply")), key=lambda p: int(re.findall(r"\d+", os.path.basename(p))[0]))
    cameras = sorted(glob.glob(os.path.join(args.dir, "camera-*.json")))
    for sp in scenes:
        means, quats, scales, opac, sh, degree = gaussians(sp, dev)
        n = means.shape[0]
        for cp in cameras:
            cam = json.load(open(cp))
            w, h = cam["width"], cam["height"]
            view = torch.tensor(cam["viewmat"], dtype=torch.float32, device=dev)[None]
            K = torch.tensor([[cam["fx"], 0, cam["cx"]], [0, cam["fy"], cam["cy"]], [0, 0, 1]], dtype=torch.float32, device=dev)[None]
            params = [t.clone().requires_grad_(True) for t in (means, quats, scales, opac, sh)]

            def render(p):
                img, alpha, meta = rasterization(p[0], p[1], p[2], p[3], p[4], view, K, w, h, near_plane=cam["near"], sh_degree=degree)
                return img, meta

            weight = torch.randn(1, h, w, 3, device=dev)

            def forward():
                with torch.no_grad():
                    render(params)

            def forward_backward():
                img, _ = render(params)
                (img * weight).sum().backward()

            with torch.no_grad():
                _, meta = render(params)
            isect = int(meta["isect_ids"].numel()) if "isect_ids" in meta else -1
            fwd = time_ms(forward, args.frames)
            fb = time_ms(forward_backward, args.frames)
            row = {"gaussians": n, "width": w, "height": h, "intersections": isect, "forward_ms": fwd[0], "forward_spread_ms": [fwd[1], fwd[2]], "forward_backward_ms": fb[0], "forward_backward_spread_ms": [fb[1], fb[2]]}
            rows.append(row)
            print(f"gsplat {n} Gaussians {w}x{h}: {isect} intersections, forward {fwd[0]:.2f} ms ({fwd[1]:.2f}-{fwd[2]:.2f}), forward+backward {fb[0]:.2f} ms ({fb[1]:.2f}-{fb[2]:.2f})", flush=True)
    if args.json:
        json.dump({"device": torch.cuda.get_device_name(0), "gsplat": gsplat.__version__, "rows": rows}, open(args.json, "w"), indent=1)


if __name__ == "__main__":
    main()
