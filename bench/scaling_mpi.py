#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""Data-parallel scaling (issues 31 and 36): `mpirun -n N uvr` over rank counts, one rank per GPU.

Strong scaling: one generated mesh (`uvr generate graded --cells STRONG`) rendered on each rank
count. Weak scaling: WEAK cells per rank (a mesh of N x WEAK cells for N ranks). For every run:

- the first image from the file: `uvr render --no-cache` wall time, with each rank's read and
  preparation seconds and peak host memory from `--stats`, and the GPUs' peak memory (sampled
  with nvidia-smi while it runs, when there is one);
- frames: `uvr bench`'s median ms per frame of the default method (auto), the reference and
  exact, with the slowest rank's frame and compositing ms;
- the picture against the fewest ranks' (`uvr compare`: SSIM, max difference);
- strong-scaling efficiency: t(first) * first / (t(N) * N) of the auto frame.

Everything goes to OUT/scaling.json; a table is printed. Meshes are generated once into OUT
(or --meshes DIR) and reused.

Usage: bench/scaling_mpi.py --uvr UVR --out DIR [--ranks 1,2,4] [--strong 1e9] [--weak 1e9]
                            [--device cuda] [--size 1024x1024] [--repeat 5]
                            [--mpirun 'mpirun --bind-to none'] [--meshes DIR]
CPU smoke run: --device cpu --strong 2e5 --weak 1e5 --size 128x128 --repeat 1.
"""
import argparse
import json
import os
import shlex
import shutil
import subprocess
import sys
import threading
import time


def run(cmd, timeout=3600):
    start = time.monotonic()
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    return r, time.monotonic() - start


class GpuMemory:
    """Peak memory.used per GPU (MiB) while a command runs, from nvidia-smi every 0.5 s."""

    def __init__(self):
        self.peak, self.stop = {}, threading.Event()
        self.thread = None
        if shutil.which("nvidia-smi"):
            self.thread = threading.Thread(target=self.poll, daemon=True)
            self.thread.start()

    def poll(self):
        while not self.stop.is_set():
            r = subprocess.run(["nvidia-smi", "--query-gpu=index,memory.used",
                                "--format=csv,noheader,nounits"], capture_output=True, text=True)
            for line in r.stdout.splitlines():
                try:
                    index, used = (int(x) for x in line.split(","))
                except ValueError:
                    continue
                self.peak[index] = max(self.peak.get(index, 0), used)
            self.stop.wait(0.5)

    def finish(self):
        self.stop.set()
        if self.thread:
            self.thread.join()
        return self.peak


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--uvr", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--ranks", default="1,2,4")
    ap.add_argument("--strong", type=float, default=1e9, help="cells of the strong-scaling mesh")
    ap.add_argument("--weak", type=float, default=1e9, help="cells per rank (0: no weak runs)")
    ap.add_argument("--device", default="cuda")
    ap.add_argument("--size", default="1024x1024")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--mpirun", default="mpirun --bind-to none")
    ap.add_argument("--meshes", help="folder of the generated meshes (default: OUT)")
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    meshes = args.meshes or args.out
    os.makedirs(meshes, exist_ok=True)
    ranks = [int(r) for r in args.ranks.split(",")]
    mpirun = shlex.split(args.mpirun)
    if os.geteuid() == 0:
        mpirun += ["--allow-run-as-root"]
    mpirun += ["--oversubscribe", "-x", "LD_LIBRARY_PATH"]
    view = ["--device", args.device, "--size", args.size, "--azimuth", "30", "--elevation", "20"]
    results = {"device": args.device, "size": args.size, "ranks": ranks, "runs": []}

    def mesh(cells):
        path = os.path.join(meshes, f"graded_{int(cells)}.uvrm")
        if not os.path.exists(path):
            r, t = run([args.uvr, "-q", "generate", "graded", "--cells", str(int(cells)),
                        "-o", path])
            if r.returncode != 0:
                sys.exit(f"generate {int(cells)} cells failed: {r.stderr.strip()}")
            print(f"generated {path} in {t:.1f} s", flush=True)
        return path

    def one_run(kind, n, path):
        tag = f"{kind}_{n}"
        image = os.path.join(args.out, f"{tag}.png")
        stats = os.path.join(args.out, f"{tag}_stats.json")
        launcher = mpirun + ["-n", str(n)]
        gpus = GpuMemory()
        r, wall = run(launcher + [args.uvr, "-q", "render", path, "--no-cache", "-o", image,
                                  "--stats", stats] + view)
        peak = gpus.finish()
        entry = {"kind": kind, "ranks": n, "mesh": os.path.basename(path)}
        if r.returncode != 0:
            entry["error"] = r.stderr.strip()[-500:]
            print(f"{tag}: render failed: {entry['error']}", flush=True)
            return entry
        with open(stats) as f:
            report = json.load(f)
        per_rank = report.get("ranks", [])
        entry.update({"first_image_seconds": wall, "gpu_peak_mib": peak,
                      "cells": report.get("cells"), "tetrahedra": report.get("tetrahedra"),
                      "host_peak_gib": max((p.get("peak_host_bytes", 0) for p in per_rank),
                                           default=0) / 2**30,
                      "render_ranks": per_rank})
        bench = os.path.join(args.out, f"{tag}_bench.json")
        r, _ = run(launcher + [args.uvr, "-q", "bench", path, "--repeat", str(args.repeat),
                               "--sweep", "16", "--json", bench] + view)
        if r.returncode != 0:
            entry["bench_error"] = r.stderr.strip()[-500:]
        else:
            with open(bench) as f:
                table = json.load(f)
            rows = table["rows"]
            entry["frames"] = {}
            if "exact" in table:
                entry["frames"]["exact"] = {"ms": table["exact"]["seconds_per_frame"] * 1e3}
            for row in rows:
                name = row["configuration"]
                if not (name.startswith("auto") or name == "reference"):
                    continue
                per = row.get("ranks") or [{}]
                entry["frames"][name] = {
                    "ms": row["seconds_per_frame"] * 1e3,
                    "slowest_rank_frame_ms": max(p.get("frame_seconds", 0) for p in per) * 1e3,
                    "slowest_rank_composite_ms":
                        max(p.get("composite_seconds", 0) for p in per) * 1e3}
        print(f"{tag}: first image {wall:.1f} s, " +
              ", ".join(f"{k} {v['ms']:.2f} ms" for k, v in entry.get("frames", {}).items()),
              flush=True)
        return entry

    def compare(entries):
        base = entries[0]
        for e in entries[1:]:
            if "error" in e or "error" in base:
                continue
            a = os.path.join(args.out, f"{base['kind']}_{base['ranks']}.png")
            b = os.path.join(args.out, f"{e['kind']}_{e['ranks']}.png")
            r, _ = run([args.uvr, "compare", a, b, "--json"])
            try:
                c = json.loads(r.stdout)
                e["against_fewest_ranks"] = {"ssim": c.get("ssim"),
                                             "max_difference": c.get("max_abs_difference")}
            except json.JSONDecodeError:
                e["against_fewest_ranks"] = {"error": r.stdout[-300:] + r.stderr[-300:]}

    strong = [one_run("strong", n, mesh(args.strong)) for n in ranks]
    compare(strong)
    first = strong[0].get("frames", {})
    for e in strong:
        for name, f in e.get("frames", {}).items():
            if name in first:
                f["efficiency"] = first[name]["ms"] * ranks[0] / (f["ms"] * e["ranks"])
    results["runs"] += strong
    if args.weak > 0:
        weak = [one_run("weak", n, mesh(args.weak * n)) for n in ranks]
        results["runs"] += weak
    with open(os.path.join(args.out, "scaling.json"), "w") as f:
        json.dump(results, f, indent=2)
    print(f"{'run':<10} {'first image s':>14} {'auto ms':>9} {'composite ms':>13} "
          f"{'efficiency':>10} {'SSIM':>8} {'max':>4}")
    for e in results["runs"]:
        auto = next((v for k, v in e.get("frames", {}).items() if k.startswith("auto")), {})
        cmp = e.get("against_fewest_ranks", {})
        print(f"{e['kind'] + '_' + str(e['ranks']):<10} {e.get('first_image_seconds', 0):>14.1f} "
              f"{auto.get('ms', 0):>9.2f} {auto.get('slowest_rank_composite_ms', 0):>13.2f} "
              f"{auto.get('efficiency', 0):>10.2f} {cmp.get('ssim') or 0:>8.5f} "
              f"{cmp.get('max_difference') or 0:>4}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
