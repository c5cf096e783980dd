//! Sort benchmark: the GPU radix sort of (u32 key, u32 value) pairs against Rust's `sort_unstable`
//! on the same data.
//!
//!   cargo bench --bench sort [-- --sizes 1000000,4000000,16000000 --runs 3 --shape ballot|lanes]
//!
//! The sort runs in the shape the device gets (sort::SortShape::for_device) unless
//! `--shape` names one; results of a named shape go to sort-<device>-<shape>.json.
//!
//! The roofline: the bytes the sort must move (sort::RadixSort::bytes_moved) over the device's compute
//! copy bandwidth is the fastest any sort with these passes could run here; the table shows the
//! sort's share of that and the ratio to `sort_unstable` a sort at the roof would reach.
//!
//! Prints a table and writes bench/results/sort-<device>.json.

#[path = "common.rs"]
mod common;

use cogeo::gpu::{Buffer, MemoryKind, Recorder};
use cogeo::rng::Rng;
use cogeo::sort::{RadixSort, SortShape};
use std::time::Instant;

fn main() {
    let args = common::args();
    let sizes = common::counts(&args, "--sizes", "1000000,4000000,16000000");
    let runs: usize = common::arg(&args, "--runs").map(|f| f.parse().unwrap()).unwrap_or(3);
    let gpu = common::gpu();
    println!("device: {}", gpu.info().summary());
    let roof = common::copy_bandwidth(&gpu);
    let named = common::arg(&args, "--shape");
    let shape = match named.as_deref() {
        None => SortShape::for_device(gpu.info()),
        Some("ballot") => SortShape::Ballot,
        Some("lanes") => SortShape::LaneSerial,
        Some(other) => panic!("--shape {other}: expected ballot or lanes"),
    };
    let mut sort = RadixSort::with_shape(&gpu, shape).unwrap();
    println!("shape: {shape:?}, {} keys per block", sort.block_keys());
    let mut rows = Vec::new();
    for &n in &sizes {
        let mut rng = Rng::new(n as u64);
        let keys: Vec<u32> = (0..n).map(|_| rng.next_u64() as u32).collect();
        let values: Vec<u32> = (0..n as u32).collect();
        sort.reserve(n as u64).unwrap();
        let k = Buffer::new(&gpu, "keys", n as u64 * 4, MemoryKind::Device).unwrap();
        let v = Buffer::new(&gpu, "values", n as u64 * 4, MemoryKind::Device).unwrap();
        let k2 = Buffer::new(&gpu, "keys alt", n as u64 * 4, MemoryKind::Device).unwrap();
        let v2 = Buffer::new(&gpu, "values alt", n as u64 * 4, MemoryKind::Device).unwrap();
        let mut gpu_ms = Vec::new();
        for run in 0..=runs {
            k.upload(&gpu, &keys).unwrap();
            v.upload(&gpu, &values).unwrap();
            let mut rec = Recorder::with_timestamps(&gpu, true).unwrap();
            let in_alt = sort.record(&mut rec, &k, &v, &k2, &v2, n as u32, 32);
            assert!(!in_alt, "32-bit keys take an even number of passes");
            rec.mark("sort");
            let t = rec.submit_and_wait().unwrap();
            if run > 0 {
                gpu_ms.push(t[0].ms); // run 0 warms up
            }
        }
        let sorted: Vec<u32> = k.download(&gpu, n).unwrap();
        assert!(sorted.windows(2).all(|w| w[0] <= w[1]), "GPU sort output is not sorted");

        let mut cpu_ms = Vec::new();
        for _ in 0..runs {
            let mut pairs: Vec<(u32, u32)> = keys.iter().copied().zip(values.iter().copied()).collect();
            let t = Instant::now();
            pairs.sort_unstable_by_key(|p| p.0);
            cpu_ms.push(t.elapsed().as_secs_f64() * 1e3);
            assert_eq!(pairs[n / 2].0, sorted[n / 2], "GPU and CPU disagree");
        }
        let g = common::median(gpu_ms);
        let c = common::median(cpu_ms);
        let mb = sort.bytes_moved(n as u64, 32) as f64 / 1e6;
        let share = mb / g / roof.roof_gbps(); // MB per ms is GB/s
        let roof_ms = mb / roof.roof_gbps();
        println!(
            "{n:>10} pairs: GPU radix {g:>9.2} ms ({:>7.1} Mkeys/s), sort_unstable {c:>9.2} ms ({:>7.1} Mkeys/s), sort_unstable/GPU {:.2}x",
            n as f64 / g / 1e3,
            n as f64 / c / 1e3,
            c / g
        );
        println!(
            "{:>10}        moves {mb:.1} MB: {:.1} % of the copy roof; at the roof {roof_ms:.2} ms, sort_unstable/roof {:.2}x",
            "",
            100.0 * share,
            c / roof_ms
        );
        rows.push(serde_json::json!({"pairs": n, "gpu_ms": g, "sort_unstable_ms": c, "speedup": c / g,
                                     "mb_moved": mb, "share_of_copy": share, "roof_ms": roof_ms,
                                     "speedup_at_roof": c / roof_ms}));
    }
    let what = format!("{shape:?} shape, median of {runs} runs");
    let mut table = common::Table::new("sort", &args, &what, Some(&gpu.info().name), "| pairs | GPU radix ms | sort_unstable ms | sort_unstable / GPU | MB moved | % of copy roof | sort_unstable / (sort at the roof) |", "|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let f = |k: &str| r[k].as_f64().unwrap();
        table.line(format!(
            "| {} | {:.1} | {:.1} | {:.2}x | {:.1} | {:.1} | {:.2}x |",
            r["pairs"],
            f("gpu_ms"),
            f("sort_unstable_ms"),
            f("speedup"),
            f("mb_moved"),
            100.0 * f("share_of_copy"),
            f("speedup_at_roof")
        ));
    }
    common::update_results(&args, "sort", &table.md);
    let suffix = named.map(|s| format!("-{s}")).unwrap_or_default();
    let path = common::results_path(&format!("sort-{}{suffix}.json", common::device_slug(&gpu)));
    common::write_json(
        &path,
        &serde_json::json!({ "device": gpu.info().summary(), "shape": format!("{shape:?}"),
                             "block_keys": sort.block_keys(), "copy_bandwidth": roof, "runs": runs, "rows": rows }),
    );
}
