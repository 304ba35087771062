//! The runner of `cargo xtask bench-ab` (bench/src/ab.rs), built once against the library of a
//! git revision and once against the working tree: the same source, so that the two differ only
//! in the library they link.
//!
//! `runner ROUNDS`: the ten cases below, each solved ROUNDS times in a row (the first of them
//! untimed), as the benchmark's Rust cases are (the scene from its file, outputs on the grid
//! t = k·0.01 s into one buffer). One line per case: `scene rtol steps ns_per_step`, the median
//! over the timed solves.
//!
//! `runner sample SCENE FORMULATION RTOL SECONDS OUT`: solves the case again and again for
//! SECONDS of CPU time with SIGPROF every 100 µs of it (the kernel's tick makes it 4 ms here),
//! and writes the interrupted instruction addresses to OUT, after the run-time address of
//! `main` (to undo the load offset).
#![allow(clippy::disallowed_methods)]

use beam_body::model::Formulation;
use beam_body::sim::{Run, Scene};
use std::time::Instant;

/// (label, scene file, formulation, rtol).
const CASES: [(&str, &str, Formulation, f64); 10] = [
    ("paper", "paper.toml", Formulation::Reduced, 1e-4),
    ("paper", "paper.toml", Formulation::Reduced, 1e-6),
    ("paper", "paper.toml", Formulation::Reduced, 1e-8),
    ("paper-dae", "paper.toml", Formulation::Dae, 1e-4),
    ("paper-dae", "paper.toml", Formulation::Dae, 1e-6),
    ("paper-dae", "paper.toml", Formulation::Dae, 1e-8),
    ("paper-dae-stabilized", "paper.toml", Formulation::DaeStabilized, 1e-4),
    ("paper-dae-stabilized", "paper.toml", Formulation::DaeStabilized, 1e-6),
    ("paper-dae-stabilized", "paper.toml", Formulation::DaeStabilized, 1e-8),
    ("stiff", "stiff.toml", Formulation::Reduced, 1e-4),
];

fn scene(file: &str, formulation: Formulation, rtol: f64) -> Scene {
    let path = format!("{}/scenes/{file}", env!("BEAM_BODY_ROOT"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    let mut s = read_scene(&text);
    s.formulation = formulation;
    s.solver.rtol = rtol;
    s
}

/// The scene of a file's text, the default absolute tolerance (1e-3·rtol), and the run at
/// t = 0: through the settings table's API ...
#[cfg(feature = "settings")]
fn read_scene(text: &str) -> Scene {
    let mut s = Scene::from_toml(text).expect("a valid scene");
    s.solver.atol = 0.0;
    s
}

#[cfg(feature = "settings")]
fn start(s: &Scene) -> Run {
    let max_steps = beam_body::solver::BdfConfig::default().max_steps;
    s.validate().expect("a valid scene");
    Run::start(s, 0.0, beam_body::model::Sample::value(0.0, 0.0), max_steps).expect("a valid run")
}

/// ... or through the API before it (revisions up to 6bbfb30).
#[cfg(not(feature = "settings"))]
fn read_scene(text: &str) -> Scene {
    let mut s = Scene::default();
    for (_, key, value) in beam_body::sim::scene_entries(text).expect("a valid scene") {
        s.set(&key, &value).expect("a valid scene key");
    }
    s.solver.atol = None;
    s
}

#[cfg(not(feature = "settings"))]
fn start(s: &Scene) -> Run {
    let model = s.validate().expect("a valid scene");
    Run::with_law(model, s.formulation, &s.solver, 0.0, s.initial, s.law).expect("a valid run")
}

fn grid(s: &Scene) -> Vec<f64> {
    let n = (s.t_end / 0.01).round() as usize;
    (0..=n).map(|k| if k == n { s.t_end } else { k as f64 * 0.01 }).collect()
}

/// One solve with the states on the grid; the accepted steps.
fn solve(s: &Scene, grid: &[f64], out: &mut Vec<f64>) -> u64 {
    out.clear();
    let mut run = start(s);
    let mut y = [0.0; 6];
    run.step_to_sampling(s.t_end, grid.iter().copied(), |run, t| {
        let n = run.state_at(t, &mut y)?;
        out.extend_from_slice(&y[..n]);
        Ok(())
    })
    .expect("the case solves");
    run.stats().steps
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("sample") {
        sample(&args[2..]);
        return;
    }
    let rounds: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(10).max(2);
    let mut out = Vec::with_capacity(1021 * 6);
    for (label, file, formulation, rtol) in CASES {
        let s = scene(file, formulation, rtol);
        let grid = grid(&s);
        let mut steps = solve(&s, &grid, &mut out);
        let mut times: Vec<f64> = (1..rounds)
            .map(|_| {
                let t0 = Instant::now();
                steps = std::hint::black_box(solve(&s, &grid, &mut out));
                t0.elapsed().as_secs_f64()
            })
            .collect();
        times.sort_by(f64::total_cmp);
        let median = times[times.len() / 2];
        println!("{label} {rtol:e} {steps} {:.2}", median * 1e9 / steps as f64);
    }
}

fn sample(args: &[String]) {
    let [scene_name, formulation, rtol, seconds, path] = args else {
        panic!("usage: runner sample SCENE FORMULATION RTOL SECONDS OUT");
    };
    let formulation = match formulation.as_str() {
        "dae" => Formulation::Dae,
        "dae_stabilized" | "dae-stabilized" => Formulation::DaeStabilized,
        "linear" => Formulation::Linear,
        _ => Formulation::Reduced,
    };
    let s = scene(&format!("{scene_name}.toml"), formulation, rtol.parse().expect("rtol"));
    let grid = grid(&s);
    let seconds: f64 = seconds.parse().expect("seconds");
    let mut out = Vec::with_capacity(grid.len() * 6);
    prof::start();
    let t0 = Instant::now();
    let mut steps = 0;
    while t0.elapsed().as_secs_f64() < seconds {
        steps += std::hint::black_box(solve(&s, &grid, &mut out));
    }
    let n = prof::stop_and_write(path, main as usize as u64);
    eprintln!(
        "{n} samples, {steps} steps, {:.1} ns per step",
        t0.elapsed().as_secs_f64() * 1e9 / steps as f64
    );
}

/// SIGPROF sampling of the instruction pointer (Linux x86-64).
mod prof {
    use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};

    const CAPACITY: usize = 1 << 20;
    static SAMPLES: [AtomicU64; CAPACITY] = [const { AtomicU64::new(0) }; CAPACITY];
    static COUNT: AtomicUsize = AtomicUsize::new(0);

    extern "C" fn on_sigprof(_: libc::c_int, _: *mut libc::siginfo_t, context: *mut libc::c_void) {
        // SAFETY: the kernel passes the interrupted context as a ucontext_t.
        let rip = unsafe {
            (*(context as *const libc::ucontext_t)).uc_mcontext.gregs[libc::REG_RIP as usize]
        };
        let i = COUNT.fetch_add(1, Ordering::Relaxed);
        if i < CAPACITY {
            SAMPLES[i].store(rip as u64, Ordering::Relaxed);
        }
    }

    fn timer(microseconds: libc::suseconds_t) {
        let period = libc::timeval { tv_sec: 0, tv_usec: microseconds };
        let timer = libc::itimerval { it_interval: period, it_value: period };
        // SAFETY: a valid itimerval; no old value is asked for.
        unsafe { libc::setitimer(libc::ITIMER_PROF, &timer, std::ptr::null_mut()) };
    }

    pub fn start() {
        // SAFETY: a zeroed sigaction with a handler of the SA_SIGINFO signature.
        unsafe {
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_sigprof as usize;
            action.sa_flags = libc::SA_SIGINFO | libc::SA_RESTART;
            libc::sigaction(libc::SIGPROF, &action, std::ptr::null_mut());
        }
        timer(100);
    }

    /// Stops the timer and writes `main`'s address, then one sample per line (hex).
    pub fn stop_and_write(path: &str, main: u64) -> usize {
        timer(0);
        let n = COUNT.load(Ordering::Relaxed).min(CAPACITY);
        let mut text = format!("{main:x}\n");
        for sample in &SAMPLES[..n] {
            text.push_str(&format!("{:x}\n", sample.load(Ordering::Relaxed)));
        }
        std::fs::write(path, text).unwrap_or_else(|e| panic!("{path}: {e}"));
        n
    }
}
