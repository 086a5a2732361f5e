//! The Dask adapter (`scripts/fluidymation_dask.py`) on a real Dask distributed cluster: a
//! `dask scheduler` and two `dask worker` processes on 127.0.0.1, started here and stopped by
//! their process ids at the end (also when a test fails).
//!
//! Needs a Python virtual environment with `dask[distributed]`, named by the environment
//! variable `FLUIDYMATION_DASK_VENV` (`.ci/run` creates one and sets it). Without it the
//! tests say so and pass — except under CI (`CI` set), where they fail.

mod farm_support;

use farm_support::*;
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

const VENV_VAR: &str = "FLUIDYMATION_DASK_VENV";

/// The virtual environment's `bin/`, or `None` (with a message) when the tests cannot run
/// here.
fn venv() -> Option<PathBuf> {
    match std::env::var_os(VENV_VAR) {
        Some(v) if Path::new(&v).join("bin/dask").is_file() => Some(Path::new(&v).join("bin")),
        v => {
            let why = match v {
                Some(v) => format!("{VENV_VAR}={} has no bin/dask", Path::new(&v).display()),
                None => format!("{VENV_VAR} is not set"),
            };
            assert!(
                std::env::var_os("CI").is_none(),
                "{why}: CI must run the Dask tests (.ci/run creates the virtual environment)"
            );
            eprintln!(
                "SKIPPED: {why}. To run the Dask tests: python3 -m venv /tmp/venv && /tmp/venv/bin/pip install \
                 'dask[distributed]' && {VENV_VAR}=/tmp/venv cargo test --release --test dask_farm"
            );
            None
        }
    }
}

/// A scheduler and two workers on 127.0.0.1; dropping it kills them (and any job process
/// they left) by process id.
struct Cluster {
    address: String,
    scheduler: Child,
    workers: Vec<Child>,
    /// Other processes to kill at the end (jobs whose worker was killed).
    strays: Vec<u32>,
}

fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

fn log_file(dir: &Path, name: &str) -> Stdio {
    Stdio::from(std::fs::File::create(dir.join(name)).unwrap())
}

impl Cluster {
    fn start(venv: &Path, logs: &Path) -> Cluster {
        let port = free_port();
        let address = format!("tcp://127.0.0.1:{port}");
        let scheduler = Command::new(venv.join("dask"))
            .args(["scheduler", "--host", "127.0.0.1", "--port", &port.to_string(), "--no-dashboard"])
            .stdout(Stdio::null())
            .stderr(log_file(logs, "scheduler.log"))
            .spawn()
            .unwrap();
        let mut cluster = Cluster { address, scheduler, workers: Vec::new(), strays: Vec::new() };
        let start = Instant::now();
        while TcpStream::connect(("127.0.0.1", port)).is_err() {
            if let Some(status) = cluster.scheduler.try_wait().unwrap() {
                panic!(
                    "dask scheduler ended ({status}): {}",
                    std::fs::read_to_string(logs.join("scheduler.log")).unwrap()
                );
            }
            assert!(start.elapsed() < Duration::from_secs(60), "the scheduler did not start listening");
            std::thread::sleep(Duration::from_millis(50));
        }
        for k in 0..2 {
            // One job at a time per worker, no nanny: the process we start is the worker.
            let worker = Command::new(venv.join("dask"))
                .args(["worker", &cluster.address, "--nthreads", "1", "--no-nanny", "--no-dashboard"])
                .args(["--host", "127.0.0.1", "--name", &format!("w{k}")])
                .stdout(Stdio::null())
                .stderr(log_file(logs, &format!("worker{k}.log")))
                .spawn()
                .unwrap();
            cluster.workers.push(worker);
        }
        cluster
    }

    fn worker_pids(&self) -> Vec<u32> {
        self.workers.iter().map(|w| w.id()).collect()
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        for pid in &self.strays {
            let _ = Command::new("kill").args(["-KILL", &pid.to_string()]).status();
        }
        for c in self.workers.iter_mut().chain(std::iter::once(&mut self.scheduler)) {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Runs the adapter on `plan` against `cluster`, waiting for both workers.
fn adapter(venv: &Path, plan: &Path, cluster: &Cluster) -> Child {
    Command::new(venv.join("python"))
        .arg(root().join("scripts/fluidymation_dask.py"))
        .arg(plan)
        .args(["--scheduler", &cluster.address, "--min-workers", "2", "--job-threads", "1"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// Waits for a process with a time limit; kills it when it is exceeded.
fn finish(child: Child, limit: Duration) -> Output {
    let pid = child.id();
    let done = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let flag = done.clone();
    let watchdog = std::thread::spawn(move || {
        let start = Instant::now();
        while !flag.load(std::sync::atomic::Ordering::SeqCst) {
            if start.elapsed() > limit {
                let _ = Command::new("kill").args(["-KILL", &pid.to_string()]).status();
                return true;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        false
    });
    let out = child.wait_with_output().unwrap();
    done.store(true, std::sync::atomic::Ordering::SeqCst);
    assert!(
        !watchdog.join().unwrap(),
        "the adapter took longer than {limit:?}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

fn write_plan(inputs: &[&Path], out: &Path, opts: &[&str], file: &Path) {
    let o = bin().arg("plan").args(inputs).arg("-o").arg(out).args(opts).output().unwrap();
    assert!(o.status.success(), "plan: {}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(file, &o.stdout).unwrap();
}

fn render(inputs: &[&Path], out: &Path, opts: &[&str]) {
    let o = bin().arg("render").args(inputs).arg("-o").arg(out).args(opts).output().unwrap();
    assert!(o.status.success(), "render: {}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn a_plan_of_two_files_on_dask_gives_the_bytes_of_render() {
    let Some(venv) = venv() else { return };
    let tmp = Scratch::new("two-files");
    let (quads, demo) = (quads(), demo());
    let opts =
        ["--scale", "0.25", "--frames", "1..4", "--seed", "9", "--keep-layers", "--style", "arm=ink-rims", "--gif"];
    let rendered = tmp.join("render");
    render(&[&quads, &demo], &rendered, &opts);

    let cluster = Cluster::start(&venv, &tmp.0);
    let out = tmp.join("dask");
    let plan = tmp.join("plan.json");
    write_plan(&[&quads, &demo], &out, &opts, &plan);
    let o = finish(adapter(&venv, &plan, &cluster), Duration::from_secs(300));
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "adapter: {err}");
    // Progress per job and a summary per file; the jobs ran on both workers.
    assert!(err.contains("11 jobs of 2 files on 2 workers"), "{err}");
    assert_eq!(err.lines().filter(|l| l.contains(" done ")).count(), 11, "{err}");
    assert!(err.contains("2 files in") && err.contains("2 rendered, 0 failed"), "{err}");
    assert!(err.contains("/quads.json ->") && err.contains("/waving.json ->"), "{err}");
    let workers: std::collections::BTreeSet<String> = err
        .lines()
        .filter(|l| l.contains(" done "))
        .filter_map(|l| l.split(" on ").nth(1))
        .map(|w| w.split_whitespace().next().unwrap_or("").trim_end_matches(':').to_string())
        .collect();
    assert_eq!(workers.len(), 2, "both workers ran jobs: {err}");
    assert_same_results(&out, &rendered);
}

/// `(pid, parent pid, command line)` of every process.
fn processes() -> Vec<(u32, u32, String)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir("/proc").unwrap().flatten() {
        let Ok(pid) = e.file_name().to_string_lossy().parse::<u32>() else { continue };
        let (Ok(stat), Ok(cmd)) =
            (std::fs::read_to_string(e.path().join("stat")), std::fs::read(e.path().join("cmdline")))
        else {
            continue;
        };
        // "pid (comm) state ppid …"; comm may hold spaces and parentheses.
        let Some(ppid) = stat.rsplit_once(')').and_then(|(_, rest)| rest.split_whitespace().nth(1)?.parse().ok())
        else {
            continue;
        };
        out.push((pid, ppid, String::from_utf8_lossy(&cmd).replace('\0', " ")));
    }
    out
}

fn signal(pid: u32, sig: &str) {
    let status = Command::new("kill").args([&format!("-{sig}"), &pid.to_string()]).status().unwrap();
    assert!(status.success(), "kill -{sig} {pid}");
}

fn alive(pid: u32) -> bool {
    // A zombie (ended, not yet reaped by its new parent) counts as ended.
    std::fs::read_to_string(format!("/proc/{pid}/stat"))
        .is_ok_and(|s| s.rsplit_once(')').is_some_and(|(_, rest)| !rest.trim_start().starts_with('Z')))
}

#[cfg(unix)]
#[test]
fn a_worker_killed_in_the_middle_of_a_layer_job_is_retried_to_the_same_bytes() {
    let Some(venv) = venv() else { return };
    let tmp = Scratch::new("kill");
    let demo = demo();
    // One stylized layer: one layer job, then the composite.
    let opts = ["--scale", "0.5", "--frames", "1..16", "--exemplar", "none", "--style", "dress=blue-bloom", "--gif"];
    let rendered = tmp.join("render");
    render(&[&demo], &rendered, &opts);

    let mut cluster = Cluster::start(&venv, &tmp.0);
    let out = tmp.join("dask");
    let plan = tmp.join("plan.json");
    write_plan(&[&demo], &out, &opts, &plan);
    let mut run = adapter(&venv, &plan, &cluster);

    // Wait until a worker's job has painted two frames, freeze the job there (so that the
    // kill surely falls in the middle), kill its worker, and let the job go on: it must stop
    // by itself, its worker being gone.
    let painted = out.join("layers/04_dress/paint/0002.png");
    let start = Instant::now();
    let (job, worker) = loop {
        if let Some(status) = run.try_wait().unwrap() {
            panic!("the adapter ended ({status}) before the layer job was under way");
        }
        assert!(start.elapsed() < Duration::from_secs(180), "the layer job never started painting");
        if painted.exists() {
            let workers = cluster.worker_pids();
            let found = processes()
                .into_iter()
                .find(|(_, ppid, cmd)| workers.contains(ppid) && cmd.contains("render-layer"))
                .map(|(pid, ppid, _)| (pid, ppid));
            if let Some(found) = found {
                break found;
            }
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    signal(job, "STOP");
    cluster.strays.push(job);
    assert!(!out.join("layers/04_dress/layer.json").exists(), "the layer job finished before the kill");
    signal(worker, "KILL");
    let index = cluster.workers.iter().position(|w| w.id() == worker).unwrap();
    cluster.workers[index].wait().unwrap();
    signal(job, "CONT");
    let t = Instant::now();
    while alive(job) {
        assert!(t.elapsed() < Duration::from_secs(10), "the orphaned job {job} did not stop after its worker died");
        std::thread::sleep(Duration::from_millis(20));
    }

    let o = finish(run, Duration::from_secs(300));
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "adapter: {err}");
    assert!(err.contains("retry: waving/04_dress"), "the job was not retried: {err}");
    assert!(err.contains("retried: waving/04_dress"), "{err}");
    // The retried job continued from its checkpoint rather than starting over.
    let line =
        err.lines().find(|l| l.contains("done") && l.contains("waving/04_dress")).unwrap_or_else(|| panic!("{err}"));
    assert!(line.contains("resumed"), "{line}");
    assert!(err.contains("1 rendered, 0 failed"), "{err}");
    assert_same_results(&out, &rendered);
}
