#!/usr/bin/python3
"""Soak: FRAMES frames of an animated scene through `ptc bench` and `ptc trace --frames` with
flat memory (issue 15): the peak resident memory after the last frame is within 5% of the peak
after the tenth (frames are numbered from 0: frames 999 and 9 of 1000).

    /usr/bin/python3 bench/soak/soak.py [--build build] [--scene armadillo-832k-twist] [--frames 1000] [--out out-soak]

Both commands record their resident and peak resident memory per frame (bench.csv and trace.csv,
columns rss_mb and peak_rss_mb); the scene's frames are extended past its listed range
(--extend-frames). Rays: 256x256 for bench, 128x128 for trace (its five images per frame are
written as well). Writes OUT/soak.csv (command, frame, rss_mb, peak_rss_mb) and OUT/manifest.json,
prints the ratio per command and exits 1 when either grows by more than 5%.
"""
import argparse
import csv
import json
import os
import shutil
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def per_frame(path):
    """frame -> (rss_mb, peak_rss_mb) of the frame's last row."""
    out = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            out[int(r["frame"])] = (float(r["rss_mb"]), float(r["peak_rss_mb"]))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--scene", default="armadillo-832k-twist")
    ap.add_argument("--frames", type=int, default=1000)
    ap.add_argument("--out", default="out-soak")
    a = ap.parse_args()
    ptc = os.path.join(a.build, "bin", "ptc")
    data = os.path.join(a.build, "data")
    tmp = a.out + ".tmp"
    shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(tmp)
    last = a.frames - 1
    # --data-dir locates built-in scenes' meshes; ptc refuses it for a mesh file or frame directory.
    where = [] if os.path.exists(a.scene) and not a.scene.lower().endswith(".json") else ["--data-dir", data]
    runs = {
        "bench": [ptc, "bench", a.scene, *where, "--frames", f"0:{last}", "--extend-frames", "--width", "256",
                  "--height", "256", "--out", os.path.join(tmp, "bench")],
        "trace": [ptc, "trace", a.scene, *where, "--frames", f"0:{last}", "--extend-frames", "--width", "128",
                  "--height", "128", "--out", os.path.join(tmp, "trace")],
    }
    rows, results, ok = [], {}, True
    for name, cmd in runs.items():
        print(f"== {' '.join(cmd)}", file=sys.stderr, flush=True)
        with open(os.path.join(tmp, name + ".log"), "wb") as log:
            if subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT).returncode != 0:
                sys.exit(f"soak: {name} failed; see {tmp}/{name}.log")
        frames = per_frame(os.path.join(tmp, name, name + ".csv"))
        order = sorted(frames)
        for f in order:
            rows.append({"command": name, "frame": f, "rss_mb": frames[f][0], "peak_rss_mb": frames[f][1]})
        f10 = order[min(9, len(order) - 1)]
        ratio = frames[order[-1]][1] / frames[f10][1]
        results[name] = {"frames": len(order), "frame_10": f10, "last_frame": order[-1], "peak_mb_frame_10": frames[f10][1],
                         "peak_mb_last_frame": frames[order[-1]][1], "ratio": ratio,
                         "rss_mb_frame_10": frames[f10][0], "rss_mb_last_frame": frames[order[-1]][0]}
        ok = ok and ratio <= 1.05
        shutil.rmtree(os.path.join(tmp, name))  # thousands of images; the per-frame figures are kept
    with open(os.path.join(tmp, "soak.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=["command", "frame", "rss_mb", "peak_rss_mb"])
        w.writeheader()
        w.writerows(rows)
    git = subprocess.run(["git", "-C", ROOT, "rev-parse", "HEAD"], capture_output=True, text=True).stdout.strip()
    json.dump({"schema": "ptc-soak/1", "argv": sys.argv, "commands": runs, "results": results, "ptc_commit": git,
               "outputs": ["soak.csv"]}, open(os.path.join(tmp, "manifest.json"), "w"), indent=2)
    if os.path.exists(a.out):
        shutil.rmtree(a.out)
        print(f"replaced the earlier {a.out}", file=sys.stderr)
    os.rename(tmp, a.out)
    for name, r in results.items():
        # Frames are numbered from 0: the tenth is frame 9.
        print(f"{name:<6} {r['frames']} frames: peak {r['peak_mb_frame_10']:.1f} MB after the tenth (frame "
              f"{r['frame_10']}), {r['peak_mb_last_frame']:.1f} MB after the last (frame {r['last_frame']}) "
              f"({r['ratio']:.3f}x; resident "
              f"{r['rss_mb_frame_10']:.1f} -> {r['rss_mb_last_frame']:.1f} MB) "
              + ("ok" if r["ratio"] <= 1.05 else "GROWS more than 5%"))
    print(f"wrote {a.out}/soak.csv, {a.out}/manifest.json")
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
