//! The M-node model of docs/farm.md: the time of a render split into one
//! tile per node, from the per-task figures that `tools/measure/farm_measure.sh`
//! measures on the local cluster, as a table (markdown, on stdout) and a
//! plot (docs/farm_model.png).
//!
//!     T(M) = L + o + W/M + m + F
//!
//! L is submission, scheduling and the wait; o a task's start-up plus its
//! driver compile (cold, or warm from a shared Mesa cache); W the render
//! itself, which alone divides over the M nodes; m the merge, serial, per
//! pixel; F the merge's reads from the shared file system (12 bytes a pixel
//! of tile parts) at one client's bandwidth. This is Amdahl's law with the
//! serial part measured rather than assumed.
//!
//!     cargo run --release -p penumbra-tools --bin farm_model -- \
//!         --latency 2.3 --overhead 0.25 --compile 1.2 --work 1.06 --work-pixels 4194304 \
//!         --merge-ns 70 [--side 16384] [--spp 64] [--bandwidth-gbs 1] [--warm] [--plot PATH]

use clap::Parser;
use plotters::prelude::*;

#[derive(Parser)]
#[command(about = "Model the time of a tiled render on M nodes from measured per-task figures")]
struct Args {
    /// L: seconds of submission, scheduling and waiting for the jobs.
    #[arg(long)]
    latency: f64,
    /// Seconds of a task's start-up (process, Vulkan, upload).
    #[arg(long)]
    overhead: f64,
    /// Seconds of the driver compile in a task with a cold Mesa cache.
    #[arg(long)]
    compile: f64,
    /// Seconds the render of `--work-pixels` pixels at one sample takes on
    /// one node.
    #[arg(long)]
    work: f64,
    /// The pixels `--work` was measured for.
    #[arg(long)]
    work_pixels: f64,
    /// Nanoseconds of the merge per pixel of the output.
    #[arg(long)]
    merge_ns: f64,
    /// Side of the modelled square image in pixels.
    #[arg(long, default_value_t = 16384)]
    side: u32,
    /// Samples per pixel of the modelled render.
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// The shared file system's bandwidth to the merging node, GB/s.
    #[arg(long, default_value_t = 1.0)]
    bandwidth_gbs: f64,
    /// Tasks load the kernel from a warmed shared Mesa cache (no compile).
    #[arg(long)]
    warm: bool,
    /// Where the plot goes.
    #[arg(long, default_value = "docs/farm_model.png")]
    plot: String,
}

/// The model's parts for M nodes, in seconds.
struct Split {
    serial: f64,
    parallel: f64,
}

impl Args {
    fn split(&self, m: f64) -> Split {
        let pixels = self.side as f64 * self.side as f64;
        let compile = if self.warm { 0.01 } else { self.compile };
        let work = self.work * pixels / self.work_pixels * self.spp as f64;
        let merge = self.merge_ns * 1e-9 * pixels;
        let files = 12.0 * pixels / (self.bandwidth_gbs * 1e9);
        Split {
            serial: self.latency + self.overhead + compile + merge + files,
            parallel: work / m,
        }
    }
}

const NODES: [u32; 10] = [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000];

fn main() -> anyhow::Result<()> {
    let args = Args::parse();
    for (name, v) in [
        ("--latency", args.latency),
        ("--overhead", args.overhead),
        ("--compile", args.compile),
        ("--work", args.work),
        ("--work-pixels", args.work_pixels),
        ("--merge-ns", args.merge_ns),
        ("--bandwidth-gbs", args.bandwidth_gbs),
    ] {
        anyhow::ensure!(
            v.is_finite() && v >= 0.0,
            "{name}: must be a finite number >= 0, got {v}"
        );
    }
    anyhow::ensure!(
        args.work > 0.0 && args.work_pixels > 0.0,
        "--work and --work-pixels: must be > 0"
    );
    anyhow::ensure!(args.bandwidth_gbs > 0.0, "--bandwidth-gbs: must be > 0");
    anyhow::ensure!(
        args.side > 0 && args.spp > 0,
        "--side and --spp: must be > 0"
    );
    let one = {
        let s = args.split(1.0);
        s.serial + s.parallel
    };
    println!(
        "{}² at {} spp, {} Mesa cache:\n",
        args.side,
        args.spp,
        if args.warm { "warm" } else { "cold" }
    );
    println!("| M nodes | T(M) | speed-up | serial share |");
    println!("|---:|---:|---:|---:|");
    let mut rows = Vec::new();
    for m in NODES {
        let s = args.split(m as f64);
        let t = s.serial + s.parallel;
        println!(
            "| {m} | {t:.0} s | {:.1} | {:.1}% |",
            one / t,
            100.0 * s.serial / t
        );
        rows.push((m as f64, t, s.serial, s.parallel));
    }
    plot(&args, &rows)
}

/// T(M), its serial floor and its dividing part against M, log-log.
fn plot(args: &Args, rows: &[(f64, f64, f64, f64)]) -> anyhow::Result<()> {
    common::plot::register_font()?;
    let (w, h) = (760u32, 480u32);
    let mut pixels = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(common::plot::err)?;
        let lo = rows.iter().map(|r| r.3.min(r.2)).fold(f64::MAX, f64::min) * 0.5;
        let hi = rows.iter().map(|r| r.1).fold(0.0, f64::max) * 2.0;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}² at {} spp on M nodes ({} Mesa cache)",
                    args.side,
                    args.spp,
                    if args.warm { "warm" } else { "cold" }
                ),
                ("sans-serif", 20),
            )
            .margin(14)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d((0.8f64..1250.0).log_scale(), (lo..hi).log_scale())
            .map_err(common::plot::err)?;
        chart
            .configure_mesh()
            .x_desc("M nodes")
            .y_desc("seconds")
            .draw()
            .map_err(common::plot::err)?;
        for (name, colour, pick) in [
            ("T(M)", BLACK, 1usize),
            ("serial: L + o + m + F", RED, 2),
            ("render W/M", BLUE, 3),
        ] {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .map(|r| (r.0, [r.1, r.2, r.3][pick - 1]))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(common::plot::err)?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new([(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(common::plot::err)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(common::plot::err)?;
        root.present().map_err(common::plot::err)?;
    }
    common::plot::save_png(pixels, w, h, &args.plot)?;
    eprintln!("wrote {}", args.plot);
    Ok(())
}
