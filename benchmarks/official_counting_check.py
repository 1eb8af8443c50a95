"""Check: ``povagent score`` on official run folders equals an independent reference, to 1e-9.

What it does:

1. copies the hand-made fixture dataset and bends it where the release can bend: a pair id
   repeated in a house (the last entry must win), an ``image_path`` repeated in an exploration
   log (its last camera must win), a ``landmark_type`` that differs from the anchor's
   ``raw_metadata.objectType`` (the surface rules follow ``landmark_type``), a non-square
   observer camera (focal length from the width) and an observer camera without a size (the
   metadata's size fills in);
2. writes an official prediction root ``POVBench_toy_0..2`` the way the official runner and
   merge step leave it: ``predictions.json`` with the size at the top level, a worker shard,
   merged per-house files (their rows are read again, as officially), ``meta.json``,
   ``eval_results.json``, a ``.jsonl`` file, an unreadable file, an object without
   predictions; and rows for unknown houses, pairs and placements, types ``A``, `` b``, ``C``,
   ``x``, a direction ``Front``, infinite coordinates, several points, missing and unknown
   frames, non-responses. Run 2 declares a 600x400 screen;
3. scores the root and one run folder with ``povagent score --json`` and compares every
   number with a reference computed here from the rules alone (raw JSON, plain floats; no
   povagent code), as the official ``eval_results.py`` and ``run_all_eval.py`` define them:
   per run, mean L2 over answered rows, response rate over every row, GT-in-frame share, the
   mean absolute signed errors (``mean_abs_x``/``mean_abs_y``), grouped by the raw type and
   direction, and the rows with a ``parse_error``; over runs, the plain mean of the runs'
   values (``n_parse_error`` summed). The root also holds a stray ``config.json`` (ignored, as
   ``run_all_eval.py`` reads folders only), and rows whose pair id differs from the file's in
   type only (``7`` for ``"7"``: no pair, officially).

Run: ``python benchmarks/official_counting_check.py [WORKDIR]``; prints the largest absolute
difference and exits 1 above 1e-9. ``tests/scoring/test_official_counting_check.py`` runs it.
"""

from __future__ import annotations

import json
import math
import random
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIXTURE = ROOT / "tests" / "fixtures" / "povbench_mini"
TOLERANCE = 1e-9
G_SPECIAL = {"Bed", "CounterTop", "Desk", "Desktop", "DiningTable", "Dresser", "SideTable"}
KEYWORDS = {
    "Bed": ["bed"], "CounterTop": ["counter", "countertop"], "Desk": ["desk"], "Desktop": ["desktop"],
    "DiningTable": ["dining table"], "Dresser": ["dresser"], "SideTable": ["side table"],
    "ArmChair": ["armchair", "arm chair"], "Chair": ["chair"], "CoffeeTable": ["coffee table"],
    "Sofa": ["sofa", "couch"], "Fridge": ["fridge", "refrigerator"], "Sink": ["sink"], "Toilet": ["toilet"],
    "WashingMachine": ["washing machine"],
}


# -- the bent dataset ---------------------------------------------------------------------------


def make_dataset(dest: Path) -> Path:
    """The fixture, bent as the module docstring says; returns its root."""
    shutil.copytree(FIXTURE, dest)
    # the fixture's deliberately broken house is the loader's subject, not this check's
    shutil.rmtree(dest / "artifacts" / "train_house_00002")
    h0 = dest / "artifacts" / "train_house_00000"
    pairs = json.loads((h0 / "train_house_00000.json").read_text())
    pairs[0]["camera"]["screen_width"], pairs[0]["camera"]["screen_height"] = 640, 480
    (h0 / "train_house_00000.json").write_text(json.dumps(pairs))
    log = json.loads((h0 / "exploration_log.json").read_text())
    moved = json.loads(json.dumps(log[0]))
    moved["camera"]["cam_yaw"] = 20.0
    log.append(moved)  # frame_000 again, turned: the last record wins
    (h0 / "exploration_log.json").write_text(json.dumps(log))
    h1 = dest / "artifacts" / "train_house_00001"
    pairs = json.loads((h1 / "train_house_00001.json").read_text())
    first = json.loads(json.dumps(pairs[0]))
    first["stage3"]["front"]["surface"] = "on the sofa"  # the earlier entry: must be replaced
    last = pairs[0]
    last["landmark_type"] = "SideTable"  # objectType stays Sofa: the rules follow landmark_type
    del last["camera"]["screen_width"], last["camera"]["screen_height"]
    (h1 / "train_house_00001.json").write_text(json.dumps([first, last]))
    return dest


# -- reference: the rules, from raw JSON --------------------------------------------------------


def load_index(root: Path) -> tuple[dict, dict]:
    """(house, pair) -> entry (last wins) and house -> image_path -> log record (last wins)."""
    index, logs = {}, {}
    for f in sorted((root / "artifacts").glob("*/train_house_*.json")):
        try:
            entries = json.loads(f.read_text())
        except ValueError:
            continue
        for e in entries if isinstance(entries, list) else []:
            index[(f.stem, e.get("pair_id", ""))] = e
        log = f.parent / "exploration_log.json"
        logs[f.stem] = {r["image_path"]: r for r in json.loads(log.read_text())} if log.exists() else {}
    return index, logs


def project(p, cam_pos, yaw, hor, fov, w, h):
    y, t = math.radians(yaw), math.radians(hor)
    d = [p[0] - cam_pos[0], p[1] - cam_pos[1], p[2] - cam_pos[2]]
    xc = d[0] * math.cos(y) - d[2] * math.sin(y)
    yc = d[0] * math.sin(y) * math.sin(t) + d[1] * math.cos(t) + d[2] * math.cos(y) * math.sin(t)
    zc = d[0] * math.sin(y) * math.cos(t) - d[1] * math.sin(t) + d[2] * math.cos(y) * math.cos(t)
    if zc <= 1e-6:
        return 0.5, 0.5, False
    f = (w / 2) / math.tan(math.radians(fov / 2))
    u, v = (f * xc / zc + w / 2) / w, (h / 2 - f * yc / zc) / h
    return min(1, max(0, u)), min(1, max(0, v)), 0 <= u <= 1 and 0 <= v <= 1


def names_anchor(surface: str, anchor: str) -> bool:
    words = KEYWORDS.get(anchor) or [" ".join(re.findall("[A-Z][a-z]*", anchor)).lower()]
    return any(k in surface for k in words)


def ground_truth(entry: dict, direction: str):
    verdict = (entry.get("stage3") or {}).get(direction)
    if not verdict or verdict.get("verdict") != "appropriate":
        pos = entry["placements"][direction]["position"]
        return pos["x"], pos["y"], pos["z"]
    surface = (verdict.get("surface") or "").lower()
    anchor = entry.get("landmark_type", "")
    box = entry["object_landmark"]["raw_metadata"]["axisAlignedBoundingBox"]
    cx, cz = box["center"]["x"], box["center"]["z"]
    hx, hz = box["size"]["x"] / 2, box["size"]["z"] / 2
    top = max(c[1] for c in box["cornerPoints"])
    if direction == "up":
        return cx, top + 0.2, cz
    cam, lm = entry["camera"]["cam_pos"], entry["object_landmark"]["position"]
    fx, fz = lm["x"] - cam[0], lm["z"] - cam[2]
    n = math.hypot(fx, fz)
    if n > 1e-6:
        fx, fz = fx / n, fz / n
    rx, rz = fz, -fx  # up x forward
    d = {"right": (rx, rz), "left": (-rx, -rz), "front": (-fx, -fz)}[direction]
    if direction in ("left", "right") and anchor in G_SPECIAL and names_anchor(surface, anchor):
        return cx + 0.2 * d[0], top + 0.2, cz + 0.2 * d[1]
    ts = [hx / abs(d[0])] if abs(d[0]) > 1e-6 else []
    ts += [hz / abs(d[1])] if abs(d[1]) > 1e-6 else []
    t = min(ts) if ts else 0.3
    y = 0.0 if "floor" in surface else top
    return cx + (t + 0.2) * d[0], y + 0.2, cz + (t + 0.2) * d[1]


def evaluate_row(row: dict, index: dict, logs: dict, sw: float, sh: float) -> dict:
    """status, error, in-frame flag of one row, by the official rules."""
    out = {"type": row["type"], "direction": row["direction"], "ok": False, "pe": bool(row.get("parse_error"))}
    x, y = row.get("predicted_x"), row.get("predicted_y")
    entry = index.get((row["house_id"], row["pair_id"]))
    if x is None or y is None or entry is None or not entry.get("placements", {}).get(row["direction"]):
        return out
    if row["type"] == "c":
        cam = entry["camera"]
        w, h = cam.get("screen_width", sw), cam.get("screen_height", sh)
    else:
        rec = logs.get(row["house_id"], {}).get(row.get("predicted_image")) if row.get("predicted_image") else None
        if rec is None:
            return out
        cam, w, h = rec["camera"], sw, sh
    gu, gv, inside = project(ground_truth(entry, row["direction"]), cam["cam_pos"], cam["cam_yaw"], cam["cam_horizon"], cam.get("fov", 100.0), w, h)
    pts = row.get("predicted_points") or [[x, y]]
    us = [min(1, max(0, p[0] / w)) for p in pts]
    vs = [min(1, max(0, p[1] / h)) for p in pts]
    err = math.hypot(sum(us) / len(us) - gu, sum(vs) / len(vs) - gv)
    # the signed errors are predicted_x/y's (a point list's first point), not the centroid's
    ex, ey = min(1, max(0, x / w)) - gu, min(1, max(0, y / h)) - gv
    return {**out, "ok": True, "l2": err, "in": inside, "ex": ex, "ey": ey}


def read_folder(folder: Path) -> tuple[list, dict]:
    rows, meta = [], {}
    for f in sorted(folder.glob("*.json")):
        if f.name in ("meta.json", "eval_results.json"):
            continue
        try:
            doc = json.loads(f.read_text())
        except ValueError:
            continue
        if isinstance(doc, list):
            rows += doc
        else:
            rows += doc.get("predictions", [])
            if not meta:
                meta = doc.get("metadata") or {k: doc[k] for k in ("screen_width", "screen_height") if k in doc}
    return rows, meta


def run_summary(folder: Path, index: dict, logs: dict) -> dict:
    """One run's cells: overall and per raw type / direction."""
    rows, meta = read_folder(folder)
    evals = [evaluate_row(r, index, logs, meta.get("screen_width", 512), meta.get("screen_height", 512)) for r in rows]

    def cell(group):
        ok = [e for e in group if e["ok"]]
        return {
            "n": len(ok),
            "n_total": len(group),
            "response_rate": len(ok) / len(group),
            "mean_l2": sum(e["l2"] for e in ok) / len(ok) if ok else None,
            "pct_in_frame": 100 * sum(e["in"] for e in ok) / len(ok) if ok else None,
            "mean_abs_x": sum(abs(e["ex"]) for e in ok) / len(ok) if ok else None,
            "mean_abs_y": sum(abs(e["ey"]) for e in ok) / len(ok) if ok else None,
        }

    out = {"overall": cell(evals), "per_condition": {}, "per_direction": {}, "n_parse_error": sum(e["pe"] for e in evals)}
    for key, field in (("per_condition", "type"), ("per_direction", "direction")):
        for label in {e[field] for e in evals}:
            out[key][label] = cell([e for e in evals if e[field] == label])
    return out


def mean_of_runs(cells: list) -> dict:
    def avg(k):
        vals = [c[k] for c in cells if c.get(k) is not None]
        return sum(vals) / len(vals) if vals else None

    return {"n": sum(c["n"] for c in cells), "n_total": sum(c["n_total"] for c in cells),
            "response_rate": avg("response_rate"), "mean_l2": avg("mean_l2"), "pct_in_frame": avg("pct_in_frame"),
            "mean_abs_x": avg("mean_abs_x"), "mean_abs_y": avg("mean_abs_y")}


def reference(root: Path, dataset: Path) -> dict:
    """The paper's aggregation over the run folders of ``root`` (one model)."""
    index, logs = load_index(dataset)
    runs = [run_summary(d, index, logs) for d in sorted(root.iterdir()) if d.is_dir()]
    out = {"overall": mean_of_runs([r["overall"] for r in runs]), "n_parse_error": sum(r["n_parse_error"] for r in runs)}
    for key in ("per_condition", "per_direction"):
        labels = set().union(*(r[key] for r in runs))
        out[key] = {k: mean_of_runs([r[key][k] for r in runs if k in r[key]]) for k in labels}
    return out


# -- the official run folders -------------------------------------------------------------------


def make_runs(root: Path, dataset: Path, seed: int = 7) -> None:
    """Three run folders of model ``toy``, as the official flow leaves them (see module docstring)."""
    rng = random.Random(seed)
    index, logs = load_index(dataset)
    for run in range(3):
        folder = root / f"POVBench_toy_{run}"
        folder.mkdir(parents=True)
        rows = []
        for (house, pair), entry in sorted(index.items(), key=str):
            frames = sorted(logs[house])
            for direction in entry["placements"]:
                for t in ("a", "b", "c"):
                    r = {"house_id": house, "pair_id": pair, "direction": direction, "type": t, "sentence": "s",
                         "predicted_x": rng.uniform(-50, 600), "predicted_y": rng.uniform(-50, 560),
                         "predicted_image": rng.choice(frames) if t != "c" else None, "parse_error": None}
                    if rng.random() < 0.15:
                        r.update(predicted_x=None, predicted_y=None, parse_error="failed to parse JSON")
                    rows.append(r)
        odd = [
            ("train_house_00000", 0, "left", "A", "exploration_images/frame_000.png"),
            ("train_house_00000", 0, "up", " b", "exploration_images/frame_002.png"),
            ("train_house_00001", "7", "front", "C", None),
            ("train_house_00001", "7", "front", "C", "exploration_images/frame_001.png"),
            ("train_house_00000", 0, "front", "x", "exploration_images/frame_001.png"),
            ("train_house_00000", 0, "Front", "c", None),
            ("train_house_00001", "7", "up", "a", "exploration_images/frame_000.png"),  # no such placement
            ("train_house_00001", "99", "left", "c", None),  # no such pair
            ("train_house_09999", 0, "left", "b", "exploration_images/frame_000.png"),  # no such house
            ("train_house_00000", 0, "left", "a", "exploration_images/frame_999.png"),  # not in the log
            ("train_house_00000", 0, "left", "b", ""),  # no selected frame
            ("train_house_00001", 7, "left", "c", None),  # the file writes "7": no such pair officially
            ("train_house_00000", "0", "left", "a", "exploration_images/frame_000.png"),  # the file writes 0
        ]
        for house, pair, direction, t, image in odd:
            rows.append({"house_id": house, "pair_id": pair, "direction": direction, "type": t,
                         "predicted_x": rng.uniform(0, 511), "predicted_y": rng.uniform(0, 511), "predicted_image": image})
        rows.append({"house_id": "train_house_00000", "pair_id": 0, "direction": "up", "type": "c",
                     "predicted_x": math.inf, "predicted_y": -math.inf})
        rows.append({"house_id": "train_house_00001", "pair_id": "7", "direction": "left", "type": "c",
                     "predicted_x": 10.0, "predicted_y": 20.0, "predicted_points": [[10, 20], [700, -40], [300, 300]]})
        size = {"screen_width": 600, "screen_height": 400} if run == 2 else {"screen_width": 512, "screen_height": 512}
        half = len(rows) // 2
        (folder / "predictions.json").write_text(json.dumps({"vlm": "toy", **size, "predictions": rows[:half]}))
        (folder / "predictions_0.json").write_text(json.dumps({"vlm": "toy", **size, "predictions": rows[half:]}))
        # the merge step's per-house files: their rows are read again by the official loader
        house0 = [r for r in rows if r["house_id"] == "train_house_00000"][:5]
        (folder / "train_house_00000.json").write_text(json.dumps(house0))
        (folder / "meta.json").write_text(json.dumps({"predictions": rows}))  # never read
        (folder / "eval_results.json").write_text(json.dumps({"summary": {}, "evaluations": rows}))  # never read
        (folder / "notes.jsonl").write_text(json.dumps(rows[0]) + "\n")  # not *.json: ignored
        (folder / "broken.json").write_text('{"predictions": [')  # unreadable: skipped
        (folder / "a_config.json").write_text(json.dumps({"temperature": 0}))  # no predictions: none read
    (root / "config.json").write_text(json.dumps({"temperature": 0}))  # beside the run folders: ignored


# -- the comparison -------------------------------------------------------------------------------


def povagent_score(predictions: Path, dataset: Path) -> dict:
    proc = subprocess.run(
        [sys.executable, "-m", "povagent.cli", "score", "--predictions", str(predictions), "--dataset", str(dataset), "--json"],
        capture_output=True, text=True, check=True,
    )
    return json.loads(proc.stdout)


def max_difference(ours: dict, ref: dict) -> float:
    """Largest absolute difference over every reference number (inf when a cell or a
    ``None`` differs)."""
    if ours.get("n_parse_error") != ref["n_parse_error"]:
        return math.inf
    worst = 0.0
    cells = [(ours["overall"], ref["overall"])]
    for key in ("per_condition", "per_direction"):
        if set(ours[key]) != set(ref[key]):
            return math.inf
        cells += [(ours[key][k], ref[key][k]) for k in ref[key]]
    for mine, theirs in cells:
        for field, value in theirs.items():
            if value is None or mine[field] is None:
                if value != mine[field]:
                    return math.inf
                continue
            worst = max(worst, abs(mine[field] - value))
    return worst


def main(workdir: Path | None = None) -> float:
    """Build everything under ``workdir`` (a temporary folder by default), compare, print."""
    work = Path(workdir) if workdir else Path(tempfile.mkdtemp(prefix="official-check-"))
    dataset = make_dataset(work / "dataset")
    root = work / "eval_results"
    make_runs(root, dataset)
    diff_root = max_difference(povagent_score(root, dataset), reference(root, dataset))
    single = root / "POVBench_toy_2"
    index, logs = load_index(dataset)
    diff_one = max_difference(povagent_score(single, dataset), run_summary(single, index, logs))
    worst = max(diff_root, diff_one)
    print(f"3-run root: max |povagent - reference| = {diff_root:.3g}; one run folder: {diff_one:.3g} (tolerance {TOLERANCE:g})")
    return worst


if __name__ == "__main__":
    sys.exit(0 if main(Path(sys.argv[1]) if len(sys.argv) > 1 else None) <= TOLERANCE else 1)
