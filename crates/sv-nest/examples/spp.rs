//! Strip-packing benchmark runner:
//! `cargo run --release -p sv-nest --example spp -- FILE --seconds 60 --seed 0 [--evals N]
//! [--searches S] [--workers W]` (default one search on two workers: two threads). With
//! `--seconds` alone the clock decides (a benchmark at equal time, as sparrow runs); with
//! `--evals` the work budget of each search does (the same layout on every machine) and the
//! seconds only cap it.
#![allow(clippy::print_stdout)]

use std::time::Duration;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut file = None;
    let mut secs = 10.0;
    let mut seed = 0;
    let mut evals = None;
    let mut searches = 1;
    let mut workers = sv_nest::strip::REFERENCE_CORES;
    let mut i = 0;
    while i < args.len() {
        match args[i].as_str() {
            "--seconds" => {
                secs = args[i + 1].parse().expect("seconds");
                i += 1;
            }
            "--evals" => {
                evals = Some(args[i + 1].parse().expect("evals"));
                i += 1;
            }
            "--workers" => {
                workers = args[i + 1].parse().expect("workers");
                i += 1;
            }
            "--searches" => {
                searches = args[i + 1].parse().expect("searches");
                i += 1;
            }
            "--seed" => {
                seed = args[i + 1].parse().expect("seed");
                i += 1;
            }
            f => file = Some(f.to_string()),
        }
        i += 1;
    }
    let file = file.expect("usage: spp FILE [--seconds S] [--seed N]");
    let inst = sv_nest::StripInstance::read(std::path::Path::new(&file)).expect("instance");
    let opts = sv_nest::StripOptions {
        seed,
        time_limit: Duration::from_secs_f64(secs),
        max_evaluations: evals,
        clock_decides: evals.is_none(),
        searches,
        workers,
        ..Default::default()
    };
    let (n, v) = inst.items.iter().fold((0, 0), |(n, v), (it, q)| {
        (n + q, v + q * it.shape_cd().vertices().len())
    });
    eprintln!(
        "{}: {n} items, {:.1} collision vertices per item, work budget per search for {secs} s: {}",
        inst.name,
        v as f64 / n.max(1) as f64,
        evals.unwrap_or_else(|| sv_nest::strip_work_budget(&inst, opts.time_limit))
    );
    let mut first = None;
    let res = sv_nest::nest_strip(&inst, &opts, &mut |p| {
        if first.is_none() {
            first = Some(p.density);
        }
        eprintln!(
            "{:8.2}s evals {:10} length {:.3} density {:.2}%",
            p.elapsed_s,
            p.evaluations,
            p.best,
            100.0 * p.density
        );
    });
    println!(
        "{} length {:.3} density {:.2} construct {:.2} evals {} time {:.1} cut {}",
        res.name,
        res.length,
        100.0 * res.density,
        100.0 * first.unwrap_or(0.0),
        res.evaluations,
        res.elapsed_s,
        res.cut_by_time
    );
}
