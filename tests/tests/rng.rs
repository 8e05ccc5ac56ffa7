//! The tests' generator is SplitMix64 exactly: seeds written into tests and benchmarks keep
//! giving the same cases.

use caveclod_tests::meshes::Rng;
use caveclod_tests::rng::SplitMix64;

#[test]
fn splitmix64_matches_the_reference_sequence() {
    // The reference implementation's first outputs from seed 0.
    let mut r = SplitMix64::new(0);
    assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
    assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    assert_eq!(r.next_u64(), 0x06C4_5D18_8009_454F);
}

#[test]
fn the_derived_draws_come_from_one_value_each() {
    let (mut a, mut b) = (SplitMix64::new(0x5eed), SplitMix64(0x5eed));
    for _ in 0..100 {
        let x = b.next_u64();
        match x % 3 {
            0 => assert_eq!(a.below(1000), (x % 1000) as usize),
            1 => assert_eq!(a.unit(), (x >> 40) as f32 / (1u64 << 24) as f32),
            _ => assert_eq!(a.unit_f64(), (x >> 11) as f64 / (1u64 << 53) as f64),
        }
        let u = SplitMix64(x).unit_f64();
        assert!((0.0..1.0).contains(&u));
    }
}

#[test]
fn the_mesh_generators_name_is_the_same_generator() {
    let (mut a, mut b) = (Rng(7), SplitMix64::new(7));
    assert_eq!(a.next_u64(), b.next_u64());
}
