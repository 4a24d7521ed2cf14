//! The study end to end: `slidestack run` on a config (default `configs/paper.yaml`, the paper's
//! full grid, both zones) into a fresh directory, printing the time of each stage (and its ratio
//! to the sweep's in the same run), cases per
//! second and simulations per second (and, for a config with an `ida:` section, the IDA's runs
//! per second and time per simulated sample).
//!
//! `cargo bench --bench study` (several minutes on 2 cores); `SLIDESTACK_BENCH_CONFIG=configs/quick.yaml`
//! for a short run.

use std::process::Command;

fn main() {
    let config =
        std::env::var("SLIDESTACK_BENCH_CONFIG").unwrap_or_else(|_| "configs/paper.yaml".into());
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into());
    let dir = std::env::temp_dir().join(format!("slidestack-bench-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_slidestack"))
        .args([
            "run",
            &config,
            "--out",
            dir.to_str().expect("utf-8 temp dir"),
        ])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs slidestack");
    let text = String::from_utf8_lossy(&out.stdout);
    if !out.status.success() {
        eprintln!("{text}{}", String::from_utf8_lossy(&out.stderr));
        std::process::exit(1);
    }
    let _ = std::fs::remove_dir_all(&dir);
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|c| {
            c.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_default();
    println!(
        "\nStudy benchmark: `slidestack run {config}` ({cpu}, {} threads, load average {load} \
         at the start)",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    // Each stage's time also as a ratio to the sweep's in the same run, the baseline row.
    println!("| stage | time (s) | × sweep |\n|---|---|---|");
    // `run` prints the stages it will run, then their times: the line with the total.
    let times = |l: &&str| l.starts_with("run: ") && l.contains(" (total ");
    if let Some(line) = text.lines().find(times) {
        let (stages, total) = line
            .trim_start_matches("run: ")
            .split_once(" (total ")
            .unwrap_or((line, ""));
        let rows: Vec<(&str, &str)> = stages
            .split(", ")
            .filter_map(|part| part.split_once(' '))
            .map(|(name, t)| (name, t.trim_end_matches(" s")))
            .chain([("total", total.trim_end_matches(" s)"))])
            .collect();
        let sweep_s = rows
            .iter()
            .find(|(name, _)| *name == "sweep")
            .and_then(|(_, t)| t.parse::<f64>().ok());
        for (name, t) in rows {
            let ratio = match (t.parse::<f64>(), sweep_s) {
                (Ok(t), Some(sweep)) if sweep > 0.0 => format!("{:.3}", t / sweep),
                _ => "–".into(),
            };
            println!("| {name} | {t} | {ratio} |");
        }
    }
    for line in text.lines().filter(|l| {
        (l.starts_with("sweep: ") && l.contains("cases/s"))
            || (l.starts_with("fit: ") && l.contains("cross-validated, in"))
            || (l.starts_with("ida: ") && l.contains("runs/s"))
    }) {
        println!("\n{line}");
    }
}
