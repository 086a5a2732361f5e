#!/usr/bin/env python3
"""Run a fluidymation plan on a Dask distributed cluster.

    fluidymation plan shots/*.json -o /shared/out --gif > plan.json
    python3 scripts/fluidymation_dask.py plan.json --scheduler tcp://HOST:8786
    python3 scripts/fluidymation_dask.py plan.json --local 2      # a cluster on this machine

A plan (see `fluidymation plan --help`) lists one `render-layer` job per stylized layer of
every input and one `composite` job per input that depends on that input's layer jobs. This
adapter submits every job to Dask with its dependencies, the costliest first (Dask runs the
ready job of highest priority first, so long layers do not end up last), prints progress as
jobs finish, and ends with one line per input file. It exits 0 when every job succeeded, 1 when
some failed (the others still run; a composite whose layer failed is skipped), 130 on Ctrl-C.

Requirements
  * Every worker runs the jobs' command lines as they are: the `fluidymation` executable
    named in the plan (or --program PATH) must exist on every worker machine, and so must the
    inputs and any exemplar folders the plan names.
  * OUT (the plan's `out`) must be on a file system that every worker shares (NFS, Lustre,
    CephFS, ...): a layer job writes its frames there, and the composite job, maybe on
    another machine, reads them. Every file is written under a temporary name and renamed,
    so a reader never sees half a file.
  * Python with `dask[distributed]` (pip install 'dask[distributed]') on the client and the
    workers, in the same version.

Failures
  * A worker that dies (killed, out of memory, machine lost) takes its job with it; the
    scheduler gives the job to another worker (up to `distributed.scheduler.allowed-failures`
    times, 3 by default; --local sets it with --allowed-failures). The job then continues from
    its last checkpoint. The adapter prints "retry" when a job starts a second time.
  * The job process stops by itself when its worker disappears (FLUIDYMATION_EXIT_WITH_PARENT),
    and a layer job holds a lock on its folder, so a retried job never runs alongside its
    orphan.
  * A job killed by a signal while its worker lives (the kernel's out-of-memory killer) is
    run again on the same worker, up to --signal-retries times. A job that fails with an
    error (exit code 1: a broken input, a missing exemplar) is not retried: it would fail
    again. --retries N retries failed jobs anyway (for flaky file systems).
"""

import argparse
import json
import os
import signal
import subprocess
import sys
import threading
import time
import uuid

_STDERR = threading.Lock()


def tell(text):
    """Writes one line on stderr, whole: the progress comes from two threads (the job starts
    arrive on Dask's event thread), and print() writes a line's text and its end separately, so
    two lines could run into each other."""
    with _STDERR:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()

EVENT_TOPIC = "fluidymation-job"


class JobFailed(Exception):
    """A job's process ended with an error."""


def _tail(text, lines=12):
    rows = [r for r in text.strip().splitlines() if r.strip()]
    return "\n".join(rows[-lines:])


def run_job(job, program, job_threads, signal_retries, *deps):
    """Runs one job of the plan on a worker; returns what it did. `deps` are the results of
    the jobs it depends on (only waited for)."""
    from distributed import get_worker

    worker = get_worker()
    argv = list(job["argv"])
    if program:
        argv[0] = program
    env = dict(os.environ, FLUIDYMATION_EXIT_WITH_PARENT="1")
    if job_threads:
        env["RAYON_NUM_THREADS"] = str(job_threads)
    attempt = 0
    while True:
        attempt += 1
        worker.log_event(
            EVENT_TOPIC, {"job": job["id"], "event": "start", "worker": worker.address, "attempt": attempt}
        )
        start = time.monotonic()
        proc = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, env=env)
        seconds = time.monotonic() - start
        if proc.returncode == 0:
            return {
                "id": job["id"],
                "worker": worker.address,
                "seconds": seconds,
                "message": _tail(proc.stderr, 3),
            }
        if proc.returncode < 0 and attempt <= signal_retries:
            continue
        how = (
            "was killed by signal %d" % -proc.returncode
            if proc.returncode < 0
            else "exited with code %d" % proc.returncode
        )
        raise JobFailed("%s %s on %s:\n%s" % (job["id"], how, worker.address, _tail(proc.stderr)))


def load_plan(path):
    try:
        with open(path, encoding="utf-8") as f:
            plan = json.load(f)
    except OSError as e:
        sys.exit("error: could not read the plan '%s': %s" % (path, e))
    except json.JSONDecodeError as e:
        sys.exit("error: '%s' is not a plan (not JSON: %s); make one with `fluidymation plan … > plan.json`" % (path, e))
    if not isinstance(plan, dict) or plan.get("format") != 1 or not isinstance(plan.get("jobs"), list):
        sys.exit("error: '%s' is not a fluidymation plan of format 1" % path)
    ids = set()
    for job in plan["jobs"]:
        for key in ("id", "kind", "argv", "deps", "cost"):
            if key not in job:
                sys.exit("error: '%s': a job has no '%s'" % (path, key))
        if job["id"] in ids:
            sys.exit("error: '%s': the job id '%s' appears twice" % (path, job["id"]))
        ids.add(job["id"])
    for job in plan["jobs"]:
        for d in job["deps"]:
            if d not in ids:
                sys.exit("error: '%s': job '%s' depends on '%s', which is not in the plan" % (path, job["id"], d))
    return plan


def topological(jobs):
    """The jobs with every job after its dependencies, costliest first where free to choose."""
    by_id = {j["id"]: j for j in jobs}
    order, state = [], {}

    def visit(job_id, path):
        if state.get(job_id) == "done":
            return
        if state.get(job_id) == "visiting":
            sys.exit("error: the plan's dependencies form a cycle: %s" % " -> ".join(path + [job_id]))
        state[job_id] = "visiting"
        for d in sorted(by_id[job_id]["deps"], key=lambda d: -by_id[d]["cost"]):
            visit(d, path + [job_id])
        state[job_id] = "done"
        order.append(by_id[job_id])

    for job in sorted(jobs, key=lambda j: -j["cost"]):
        visit(job["id"], [])
    return order


def check_workers(client, plan, program):
    """Every worker must see the plan's executable and the folder of OUT (a shared file
    system)."""
    exe = program or (plan["jobs"][0]["argv"][0] if plan["jobs"] else None)
    out_parent = os.path.dirname(os.path.abspath(plan["out"].rstrip("/")))

    def probe(exe=exe, folder=out_parent):
        return {
            "exe": exe is None or (os.path.isfile(exe) and os.access(exe, os.X_OK)),
            "out": os.path.isdir(folder),
        }

    problems = []
    for worker, seen in sorted(client.run(probe).items()):
        if not seen["exe"]:
            problems.append("worker %s cannot run '%s' (give --program PATH)" % (worker, exe))
        if not seen["out"]:
            problems.append(
                "worker %s does not see '%s': OUT must be on a file system every worker shares" % (worker, out_parent)
            )
    if problems:
        sys.exit("error: " + "\n  ".join(problems))


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Run a fluidymation plan (fluidymation plan … > plan.json) on a Dask distributed cluster.",
        epilog="OUT must be on a file system every worker shares; see the module documentation.",
    )
    parser.add_argument("plan", help="the plan, as written by `fluidymation plan`")
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--scheduler", metavar="ADDRESS", help="the scheduler's address, e.g. tcp://HOST:8786")
    where.add_argument("--local", metavar="N", type=int, help="start a local cluster of N single-job workers")
    parser.add_argument("--program", metavar="PATH", help="the fluidymation executable on the workers [default: the plan's]")
    parser.add_argument(
        "--job-threads",
        metavar="N",
        type=int,
        help="threads of each job (RAYON_NUM_THREADS) [default: all cores of its machine]",
    )
    parser.add_argument("--retries", metavar="N", type=int, default=0, help="retry failed jobs N times [default: 0]")
    parser.add_argument(
        "--signal-retries",
        metavar="N",
        type=int,
        default=2,
        help="run a job killed by a signal (while its worker lives) again, N times [default: 2]",
    )
    parser.add_argument(
        "--allowed-failures",
        metavar="N",
        type=int,
        default=3,
        help="with --local: how many workers may die running one job before it fails [default: 3]",
    )
    parser.add_argument(
        "--min-workers",
        metavar="N",
        type=int,
        default=1,
        help="wait until N workers have joined before starting [default: 1]",
    )
    parser.add_argument("-q", "--quiet", action="store_true", help="print only failures and the summary")
    args = parser.parse_args(argv)
    if args.local is not None and args.local < 1:
        parser.error("--local N needs N >= 1")

    plan = load_plan(args.plan)
    jobs = topological(plan["jobs"])
    total_cost = sum(j["cost"] for j in jobs) or 1

    import dask
    from distributed import Client, LocalCluster, as_completed

    def say(text):
        if not args.quiet:
            tell(text)

    cluster = None
    if args.local is not None:
        dask.config.set({"distributed.scheduler.allowed-failures": args.allowed_failures})
        cluster = LocalCluster(
            n_workers=args.local, threads_per_worker=1, processes=True, dashboard_address=None
        )
        client = Client(cluster)
    else:
        client = Client(args.scheduler, timeout="30s")
    try:
        client.wait_for_workers(args.min_workers if args.local is None else args.local, timeout=300)
        check_workers(client, plan, args.program)
        workers = len(client.scheduler_info()["workers"])
        say("%d jobs of %d files on %d workers (%s)" % (len(jobs), len(plan.get("files", [])), workers, client.scheduler.address))

        starts = {}
        lock = threading.Lock()

        def on_event(event):
            _, msg = event
            if not isinstance(msg, dict) or msg.get("event") != "start":
                return
            with lock:
                starts[msg["job"]] = starts.get(msg["job"], 0) + 1
                n = starts[msg["job"]]
            if n > 1 and msg.get("attempt", 1) == 1:
                tell("retry: %s started again on %s (the worker running it was lost)" % (msg["job"], msg["worker"]))
            elif n > 1:
                tell("retry: %s run again on %s (it was killed by a signal)" % (msg["job"], msg["worker"]))
            else:
                say("start  %s on %s" % (msg["job"], msg["worker"]))

        client.subscribe_topic(EVENT_TOPIC, on_event)

        # Composites run as soon as their layers are done; among layers the costliest first.
        top = max(j["cost"] for j in jobs) + 1 if jobs else 1
        token = uuid.uuid4().hex[:8]
        futures, job_of = {}, {}
        for job in jobs:
            deps = [futures[d] for d in job["deps"]]
            priority = 2 * top if job["kind"] == "composite" else job["cost"]
            f = client.submit(
                run_job,
                job,
                args.program,
                args.job_threads,
                args.signal_retries,
                *deps,
                key="fluidymation-%s-%s" % (token, job["id"]),
                priority=priority,
                retries=args.retries,
                pure=False,
            )
            futures[job["id"]] = f
            job_of[f.key] = job

        start = time.monotonic()
        done_cost, finished, failed = 0, 0, {}
        for f in as_completed(list(futures.values())):
            job = job_of[f.key]
            finished += 1
            done_cost += job["cost"]
            progress = "[%*d/%d] %3d%%" % (len(str(len(jobs))), finished, len(jobs), 100 * done_cost // total_cost)
            if f.status == "finished":
                r = f.result()
                # The job's own last line, without the output path the plan already names.
                said = r["message"].splitlines()[-1].split(" -> ")[0] if r["message"] else ""
                say("%s  done   %s in %.1f s on %s: %s" % (progress, job["id"], r["seconds"], r["worker"], said))
            else:
                exc = f.exception()
                failed[job["id"]] = exc
                failing_dep = next((d for d in job["deps"] if futures[d].status == "error"), None)
                if failing_dep is not None:
                    tell("%s  SKIPPED %s: its job %s failed" % (progress, job["id"], failing_dep))
                else:
                    tell("%s  FAILED %s: %s" % (progress, job["id"], exc))

        elapsed = time.monotonic() - start
        retried = sorted(j for j, n in starts.items() if n > 1)
        files = plan.get("files", [])
        bad = [fl for fl in files if fl["composite_job"] in failed]
        tell(
            "%d files in %.1f s: %d rendered, %d failed%s"
            % (len(files), elapsed, len(files) - len(bad), len(bad), (" (retried: %s)" % ", ".join(retried)) if retried else "")
        )
        for fl in files:
            if fl["composite_job"] in failed:
                culprits = [j for j in fl["layer_jobs"] + [fl["composite_job"]] if j in failed and futures[j].status == "error"]
                first = next((j for j in culprits if not any(futures[d].status == "error" for d in next(x for x in jobs if x["id"] == j)["deps"])), culprits[0])
                tell("  FAILED  %s: %s" % (fl["input"], failed[first]))
            elif not args.quiet:
                tell("  ok      %s -> %s%s" % (fl["input"], fl["out_dir"], (", " + fl["gif"]) if fl.get("gif") else ""))
        return 1 if failed else 0
    except KeyboardInterrupt:
        tell("interrupted; run the same command again: finished jobs are skipped, layers continue from their checkpoints")
        return 130
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


if __name__ == "__main__":
    signal.signal(signal.SIGINT, signal.default_int_handler)
    sys.exit(main())
