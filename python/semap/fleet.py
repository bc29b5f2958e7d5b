"""Fleet mapping on Dask (issue 23): many recordings mapped in parallel, merged into one map.

    python3 -m semap.fleet DATASET... --out OUT [--scheduler tcp://HOST:PORT] [--config C.yaml]
                           [--segmenter SPEC] [--workers N] [--retries N]

One Dask task per recording maps it with semap.run into OUT/<name>/ (published as a whole, as
`semap run` does: a retried task never leaves a mixed folder). Then the maps are merged as a
tree of pairwise merges (semap.merge_maps, also Dask tasks, so merges spread over workers):
each round pairs up the components not yet tried together, a pair that relocalises becomes one
component, one that does not stays apart. The largest component is published as OUT/merged/
(map.semap, mesh.ply, objects, and each recording's trajectory in the merged world frame as
<name>.trajectory.txt); recordings that relocalise into nothing are reported and kept as their
own components (OUT/<name>/), never forced in.

Without --scheduler a LocalCluster with one single-threaded worker process per core runs the
same code. Faults: a worker that dies mid-task is replaced by the scheduler (its task runs again
elsewhere); a recording that fails with a semap error is reported with that error and the
others still merge.

Outputs never replace files the fleet did not write (issue 44): OUT may not be nor contain a
recording; OUT/.fleet (the merges' work folder) is removed only when it carries the fleet's
marker, and OUT/fleet.json is replaced only when an earlier fleet run wrote it. Each
OUT/<name>/ goes through semap.run's own output-folder rule. The LocalCluster and its dashboard
listen on 127.0.0.1 only; give --scheduler to use other machines.
"""

import argparse
import json
import os
import pathlib
import shutil
import sys
import time

_TRAJECTORY_SUFFIX = ".trajectory.txt"
_WORK_MARKER = ".semap-fleet-work"  # in OUT/.fleet: the fleet made this folder, may remove it
_FLEET_KEY = "semap_fleet"  # in OUT/fleet.json: written by the fleet, may be replaced


# --- tasks (run on the workers) ------------------------------------------------------------

def map_recording(dataset, out_dir, config, segmenter):
    """One recording -> OUT/<name>/ (semap.run). Returns a small summary."""
    import semap

    t0 = time.monotonic()
    report = semap.run(dataset, out_dir, config=config, segmenter=segmenter or "", progress=False)
    summary = report.get("summary", {})
    return {"frames": summary.get("frames"), "keyframes": summary.get("keyframes"),
            "ate_rmse_m": ((report.get("evaluation") or {}).get("ate") or {}).get("rmse_m"),
            "wall_s": time.monotonic() - t0}


def merge_components(a, b, out_dir):
    """Merges component b into component a (semap.merge_maps). Returns the report's summary."""
    import semap

    t0 = time.monotonic()
    report = semap.merge_maps(a["folder"], b["folder"], out_dir)
    summary = dict(report["summary"])
    summary["wall_s"] = time.monotonic() - t0
    return summary


# --- the driver ------------------------------------------------------------------------------

def recording_names(datasets):
    """Output folder names: the datasets' base names, made unique."""
    names, used = [], set()
    for d in datasets:
        base = pathlib.Path(d).resolve().name or "recording"
        name, k = base, 2
        while name in used or name in ("merged", ".fleet"):
            name, k = "%s_%d" % (base, k), k + 1
        used.add(name)
        names.append(name)
    return names


class Progress:
    """One status line per change: recordings done / running / failed, merges."""

    def __init__(self, total):
        self.total, self.last = total, None

    def show(self, futures, phase):
        states = [f.status for f in futures]
        line = "semap.fleet: %s: %d/%d done, %d running or queued, %d failed" % (
            phase, states.count("finished"), len(states), states.count("pending"), states.count("error"))
        if line != self.last:
            print(line, flush=True)
            self.last = line


def wait_all(futures, progress, phase):
    """Until every task has finished or failed, showing progress when it changes."""
    while True:
        progress.show(futures, phase)
        if all(f.status in ("finished", "error", "cancelled") for f in futures):
            return
        time.sleep(1.0)


def map_all(client, datasets, names, out, config, segmenter, retries):
    futures = [client.submit(map_recording, str(d), str(out / n), config, segmenter, key="map-" + n,
                             retries=retries, pure=False) for d, n in zip(datasets, names)]
    wait_all(futures, Progress(len(futures)), "mapping")
    mapped, failed = {}, {}
    for n, f in zip(names, futures):
        if f.status == "finished":
            mapped[n] = f.result()
        else:
            failed[n] = "%s: %s" % (type(f.exception()).__name__, f.exception())
    return mapped, failed


def untried_pairs(components, tried):
    """A matching of the components: neighbours in recording order first (sequential
    recordings overlap most), each component in at most one pair."""
    pairs, used = [], set()
    for i, a in enumerate(components):
        for j in range(i + 1, len(components)):
            b = components[j]
            key = frozenset([a["id"], b["id"]])
            if i in used or j in used or key in tried:
                continue
            pairs.append((i, j))
            used.update((i, j))
            tried.add(key)
            break
    return pairs


def merge_tree(client, components, work, retries):
    """Pairwise merges, round by round, until no untried pair is left. Returns the components
    and a log of the merges."""
    tried, log, round_no = set(), [], 0
    while len(components) > 1:
        pairs = untried_pairs(components, tried)
        if not pairs:
            break
        round_no += 1
        futures = []
        for k, (i, j) in enumerate(pairs):
            out_dir = work / ("merge-%d-%d" % (round_no, k))
            futures.append(client.submit(merge_components, components[i], components[j], str(out_dir),
                                         key="merge-%d-%d" % (round_no, k), retries=retries, pure=False))
        wait_all(futures, Progress(len(futures)), "merge round %d" % round_no)
        replaced, dropped = {}, set()
        for k, ((i, j), f) in enumerate(zip(pairs, futures)):
            a, b = components[i], components[j]
            entry = {"a": a["recordings"], "b": b["recordings"]}
            if f.status == "finished" and f.result()["merged"]:
                entry.update(f.result())
                # The merged component takes A's place: A's world frame, recordings in order.
                replaced[i] = {"id": "m%d-%d" % (round_no, k), "folder": str(work / ("merge-%d-%d" % (round_no, k))),
                               "recordings": a["recordings"] + b["recordings"], "merged": True}
                dropped.add(j)
            else:
                entry.update(f.result() if f.status == "finished" else {"merged": False, "reason": str(f.exception())})
            log.append(entry)
        components = [replaced.get(i, c) for i, c in enumerate(components) if i not in dropped]
    return components, log


def publish_component(component, out, target):
    """Copies the chosen component's map into OUT/merged as a whole: a staging folder renamed
    into place (the previous OUT/merged, made by an earlier fleet run, is replaced)."""
    staging = out / (".merged-staging-%d" % os.getpid())
    shutil.rmtree(staging, ignore_errors=True)
    source = pathlib.Path(component["folder"])
    shutil.copytree(source, staging, ignore=shutil.ignore_patterns(".semap-*"))
    if not component.get("merged"):  # one recording: its trajectory under its name
        (staging / "trajectory.txt").rename(staging / (component["recordings"][0] + _TRAJECTORY_SUFFIX))
    (staging / "fleet.json").write_text(json.dumps({"recordings": component["recordings"]}, indent=2) + "\n")
    old = out / (".merged-old-%d" % os.getpid())
    if target.exists():
        if not (target / "fleet.json").exists():
            shutil.rmtree(staging, ignore_errors=True)
            raise SystemExit("semap.fleet: error: %s exists and was not written by semap.fleet; nothing replaced" % target)
        target.rename(old)
    staging.rename(target)
    shutil.rmtree(old, ignore_errors=True)


def output_problem(out, datasets):
    """Why OUT cannot take the fleet's outputs (a line), or None: OUT is or contains a
    recording, or holds a .fleet / fleet.json the fleet did not write."""
    out_r = out.resolve()
    for d in datasets:
        d_r = pathlib.Path(d).resolve()
        if d_r == out_r:
            return "%s is the recording %s itself: give another --out" % (out, d)
        if out_r in d_r.parents:
            return "%s contains the recording %s: give an --out outside the recordings" % (out, d)
    work = out / ".fleet"
    if (work.exists() or work.is_symlink()) and not (work.is_dir() and not work.is_symlink()
                                                     and (work / _WORK_MARKER).is_file()):
        return "%s exists and was not made by semap.fleet: refusing to remove it" % work
    summary = out / "fleet.json"
    if summary.exists() or summary.is_symlink():
        try:
            written_by_fleet = not summary.is_symlink() and _FLEET_KEY in json.loads(summary.read_text())
        except (OSError, ValueError, TypeError):
            written_by_fleet = False
        if not written_by_fleet:
            return "%s exists and was not written by semap.fleet: refusing to replace it" % summary
    return None


def make_work_folder(out):
    """OUT/.fleet, fresh, with the marker that lets a later run remove it."""
    work = out / ".fleet"
    if (work / _WORK_MARKER).is_file():
        shutil.rmtree(work)
    work.mkdir()
    (work / _WORK_MARKER).write_text("semap.fleet work folder (removed when the fleet ends)\n")
    return work


def remove_work_folder(out):
    work = out / ".fleet"
    if work.is_dir() and not work.is_symlink() and (work / _WORK_MARKER).is_file():
        shutil.rmtree(work, ignore_errors=True)


def make_client(scheduler, workers):
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout="30s"), None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                           host="127.0.0.1", dashboard_address="127.0.0.1:0")  # issue 44: local only
    return Client(cluster), cluster


def summary_table(names, mapped, failed, log, components, merged_recordings, wall_s):
    rows = []
    for n in names:
        if n in failed:
            rows.append((n, "failed", failed[n]))
        else:
            m = mapped[n]
            where = "merged" if n in merged_recordings else "own component (did not relocalise)"
            ate = "" if m.get("ate_rmse_m") is None else ", ATE %.2f cm" % (100 * m["ate_rmse_m"])
            rows.append((n, where, "%s frames, %s keyframes, %.1f s%s" % (m["frames"], m["keyframes"], m["wall_s"], ate)))
    width = max([len(r[0]) for r in rows] + [9])
    lines = ["-" * (width + 60)]
    lines += ["%-*s  %-34s %s" % (width, *r) for r in rows]
    lines.append("-" * (width + 60))
    for e in log:
        lines.append("merge %s + %s: %s" % ("+".join(e["a"]), "+".join(e["b"]),
                                           "merged (%d of %d keyframes relocalised, %.1f s)" % (
                                               e["keyframes_b_relocalised"], e["keyframes_b"], e["wall_s"])
                                           if e.get("merged") else "not merged: %s" % e.get("reason", "")))
    lines.append("components: %d; wall time %.1f s" % (len(components), wall_s))
    return "\n".join(lines)


def parse_args(argv):
    p = argparse.ArgumentParser(prog="python3 -m semap.fleet",
                                description="Map many recordings in parallel on Dask and merge them into one map")
    p.add_argument("datasets", nargs="+", help="dataset folders or files (anything `semap run` reads)")
    p.add_argument("--out", required=True, help="output folder: OUT/<name>/ per recording, OUT/merged/")
    p.add_argument("--scheduler", help="Dask scheduler address (tcp://HOST:PORT); default: a LocalCluster")
    p.add_argument("--config", help="YAML config for every recording (see `semap config --dump`)")
    p.add_argument("--segmenter", help="segmenter spec for every recording (yolo:MODEL, none, ...)")
    p.add_argument("--workers", type=int, default=0, help="LocalCluster workers (default: one per core)")
    p.add_argument("--retries", type=int, default=2, help="retries of a task that raised (Dask task retries)")
    return p.parse_args(argv)


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    out = pathlib.Path(args.out)
    for d in args.datasets:
        if not pathlib.Path(d).exists():
            what = "a dangling symlink" if pathlib.Path(d).is_symlink() else "not found"
            print("semap.fleet: error: %s: %s" % (d, what), file=sys.stderr)
            return 1
    if args.config and not pathlib.Path(args.config).is_file():
        print("semap.fleet: error: %s: not a file" % args.config, file=sys.stderr)
        return 1
    problem = output_problem(out, args.datasets)
    if problem:
        print("semap.fleet: error: %s" % problem, file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    names = recording_names(args.datasets)
    t0 = time.monotonic()
    client, cluster = make_client(args.scheduler, args.workers)
    try:
        if client.dashboard_link:
            print("semap.fleet: Dask dashboard at %s" % client.dashboard_link, flush=True)
        mapped, failed = map_all(client, args.datasets, names, out, args.config, args.segmenter, args.retries)
        for n, why in failed.items():
            print("semap.fleet: %s failed: %s" % (n, why), file=sys.stderr, flush=True)
        components = [{"id": n, "folder": str(out / n), "recordings": [n], "merged": False} for n in names if n in mapped]
        if not components:
            print("semap.fleet: error: every recording failed; nothing merged", file=sys.stderr)
            return 1
        work = make_work_folder(out)
        components, log = merge_tree(client, components, work, args.retries)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    components.sort(key=lambda c: -len(c["recordings"]))
    publish_component(components[0], out, out / "merged")
    remove_work_folder(out)
    merged_recordings = set(components[0]["recordings"]) if len(components[0]["recordings"]) > 1 else set()
    (out / "fleet.json").write_text(json.dumps({_FLEET_KEY: 1, "recordings": names, "mapped": mapped, "failed": failed,
                                                "merges": log, "components": [c["recordings"] for c in components]},
                                               indent=2) + "\n")
    print(summary_table(names, mapped, failed, log, components, merged_recordings, time.monotonic() - t0))
    print("merged map in %s" % (out / "merged"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
