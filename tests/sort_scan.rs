//! GPU radix sort and prefix scan against CPU references: duplicates, sizes around workgroup and
//! block boundaries, partial key widths, stability.

mod common;

use cogeo::gpu::{Buffer, MemoryKind, Recorder};
use cogeo::rng::Rng;
use cogeo::sort::scan::{PrefixScan, ScanShape};
use cogeo::sort::{RadixSort, SortShape, LANE_SERIAL_MAX_LANES};
use common::gpu;

/// Sorts (key, index) pairs on the GPU and checks against Rust's stable sort.
fn check_sort(g: &cogeo::gpu::Gpu, sort: &mut RadixSort, keys: &[u32], bits: u32) {
    let n = keys.len();
    let values: Vec<u32> = (0..n as u32).collect();
    sort.reserve(n as u64).unwrap();
    let k = Buffer::from_slice(g, "keys", keys).unwrap();
    let v = Buffer::from_slice(g, "values", &values).unwrap();
    let k2 = Buffer::new(g, "keys alt", n as u64 * 4, MemoryKind::Device).unwrap();
    let v2 = Buffer::new(g, "values alt", n as u64 * 4, MemoryKind::Device).unwrap();
    let mut rec = Recorder::new(g).unwrap();
    let in_alt = sort.record(&mut rec, &k, &v, &k2, &v2, n as u32, bits);
    rec.submit_and_wait().unwrap();
    let (rk, rv) = if in_alt { (&k2, &v2) } else { (&k, &v) };
    let got_keys: Vec<u32> = rk.download(g, n).unwrap();
    let got_values: Vec<u32> = rv.download(g, n).unwrap();

    let mask = if bits >= 32 { u32::MAX } else { (1u32 << bits) - 1 };
    let mut expected: Vec<(u32, u32)> = keys.iter().copied().zip(values).collect();
    expected.sort_by_key(|&(key, _)| key & mask); // stable
    for i in 0..n {
        assert_eq!(
            (got_keys[i], got_values[i]),
            expected[i],
            "{:?} shape, n = {n}, bits = {bits}: mismatch at {i} (GPU key {:#x}, value {})",
            sort.shape(),
            got_keys[i],
            got_values[i]
        );
    }
}

/// Both shapes of the sort, whichever the device would pick: each is checked everywhere. The
/// lane-serial shape has counter rows for at most LANE_SERIAL_MAX_LANES lanes and says so beyond.
fn both_shapes(g: &cogeo::gpu::Gpu) -> Vec<RadixSort> {
    let mut sorts = vec![RadixSort::with_shape(g, SortShape::Ballot).unwrap()];
    match RadixSort::with_shape(g, SortShape::LaneSerial) {
        Ok(sort) => sorts.push(sort),
        Err(e) => {
            assert!(g.info().subgroup_size > LANE_SERIAL_MAX_LANES, "lane-serial sort failed: {e:#}");
            eprintln!("lane-serial shape not available here: {e:#}");
        }
    }
    assert_eq!(RadixSort::new(g).unwrap().shape(), SortShape::for_device(g.info()));
    sorts
}

#[test]
fn radix_sort_matches_stable_cpu_sort_around_block_boundaries() {
    let g = gpu();
    for mut sort in both_shapes(&g) {
        let b = sort.block_keys() as usize;
        // a lane's slice in the lane-serial shape is b / subgroup keys: cut inside, at and past
        // slices, and off uvec4 boundaries
        let slice = b / g.info().subgroup_size as usize;
        let mut rng = Rng::new(3);
        for &n in &[
            1usize,
            2,
            15,
            16,
            17,
            255,
            256,
            257,
            slice - 1,
            slice,
            slice + 1,
            3 * slice + 2,
            b - 1,
            b,
            b + 1,
            2 * b - 1,
            2 * b + 1,
            3 * b + 77,
            100_003,
        ] {
            let full: Vec<u32> = (0..n).map(|_| rng.next_u64() as u32).collect();
            check_sort(&g, &mut sort, &full, 32);
            // heavy duplicates: stability decides the value order
            let dups: Vec<u32> = (0..n).map(|_| (rng.next_u64() % 7) as u32).collect();
            check_sort(&g, &mut sort, &dups, 32);
        }
    }
}

#[test]
fn radix_sort_partial_key_widths_and_degenerate_inputs() {
    let g = gpu();
    for mut sort in both_shapes(&g) {
        partial_widths_and_degenerate_inputs(&g, &mut sort);
    }
}

fn partial_widths_and_degenerate_inputs(g: &cogeo::gpu::Gpu, sort: &mut RadixSort) {
    let mut rng = Rng::new(5);
    let n = 50_000;
    // 13 bits (tile ids at 1080p), 31 bits (positive float depths), odd pass counts (5 bits -> 1,
    // 17 -> 3) and a last pass narrower than a digit (9, 13, 17, 31)
    for bits in [5u32, 9, 13, 17, 31] {
        let keys: Vec<u32> = (0..n).map(|_| (rng.next_u64() as u32) & ((1u32 << bits) - 1)).collect();
        check_sort(g, sort, &keys, bits);
    }
    // only the low bits are sorted on: high bits must travel with the key but not order it
    let keys: Vec<u32> = (0..n).map(|_| rng.next_u64() as u32).collect();
    check_sort(g, sort, &keys, 8);
    // ... also where the width ends inside a digit: bits 13-15 share the second digit with 8-12
    check_sort(g, sort, &keys, 13);
    check_sort(g, sort, &vec![42u32; n], 32);
    let descending: Vec<u32> = (0..n as u32).rev().collect();
    check_sort(g, sort, &descending, 32);
    let floats: Vec<u32> = (0..n).map(|_| (rng.range(0.01, 100.0) as f32).to_bits()).collect();
    check_sort(g, sort, &floats, 31);
}

#[test]
fn prefix_scan_matches_cpu_exclusive_scan() {
    let g = gpu();
    assert_eq!(PrefixScan::new(&g).unwrap().shape(), ScanShape::for_device(g.info()));
    for shape in [ScanShape::Tree, ScanShape::LaneSerial] {
        let mut scan = PrefixScan::with_shape(&g, shape).unwrap();
        let mut rng = Rng::new(9);
        let b = shape.block() as usize;
        // a lane's slice in the lane-serial shape: cut inside, at and past slices, off uvec4s
        let slice = b / g.info().subgroup_size as usize;
        // sizes that need one, two and three levels
        for &n in &[1usize, 3, 5, slice - 1, slice + 2, b - 1, b, b + 1, b * 3 + 7, b * b - 1, b * b + 5, 2_500_000] {
            let data: Vec<u32> = (0..n).map(|_| (rng.next_u64() % 100) as u32).collect();
            scan.reserve(n as u64).unwrap();
            let buf = Buffer::from_slice(&g, "scan data", &data).unwrap();
            let mut rec = Recorder::new(&g).unwrap();
            scan.record(&mut rec, &buf, n as u32);
            rec.submit_and_wait().unwrap();
            let got: Vec<u32> = buf.download(&g, n).unwrap();
            let mut acc = 0u32;
            for i in 0..n {
                assert_eq!(got[i], acc, "{shape:?}, n = {n}: mismatch at {i}");
                acc += data[i];
            }
        }
    }
}

#[test]
fn every_buffer_starts_16_byte_aligned() {
    // the lane-serial sort and the loss's vec4 passes read uvec4s / vec4s from a buffer's start
    let g = gpu();
    let buffers: Vec<Buffer> =
        (1..=9u64).map(|words| Buffer::new(&g, "odd", 4 * words + 4, MemoryKind::Device).unwrap()).collect();
    for b in &buffers {
        assert_eq!(b.address() % 16, 0, "buffer at {:#x} is not 16-byte aligned", b.address());
    }
}
