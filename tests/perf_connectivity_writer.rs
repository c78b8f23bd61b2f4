//! The connectivity block writer (`output::connectivity::write_block`, fixed runs of keys copied
//! whole, integers two digits at a time) against serde_json on blocks with random integers of
//! every width (0, one digit, powers of ten and their neighbours, `usize::MAX`, `i32::MIN`),
//! random optional fields and names needing escapes.

use medial_blocks::connectivity::{
    BlockConnectivity, Cgns1to1, Partner, SideConnectivity, SideKind,
};
use medial_blocks::layouts::SplitMix64;
use medial_blocks::output::connectivity::write_block;

/// An unsigned integer of a random width, often at a power of ten or next to one.
fn unsigned(rng: &mut SplitMix64) -> usize {
    let digits = (rng.next_u64() % 21) as u32;
    let base = if digits == 20 {
        usize::MAX
    } else {
        10usize.pow(digits.min(19))
    };
    match rng.next_u64() % 4 {
        0 => base,
        1 => base.saturating_sub(1),
        2 => base.saturating_add(1),
        _ => (rng.next_u64() as usize) % base.max(1),
    }
}

fn signed(rng: &mut SplitMix64) -> i32 {
    match rng.next_u64() % 6 {
        0 => i32::MIN,
        1 => i32::MAX,
        2 => 0,
        3 => -((unsigned(rng) % 1_000_000_000) as i32),
        _ => rng.next_u64() as i32,
    }
}

fn side(rng: &mut SplitMix64) -> SideConnectivity {
    let names = [
        "j_min",
        "i_max",
        "j_max",
        "i_min",
        "odd \"name\"\n",
        "é",
        "",
    ];
    let maybe = |rng: &mut SplitMix64| rng.next_u64().is_multiple_of(2);
    SideConnectivity {
        side: unsigned(rng),
        name: names[(rng.next_u64() % names.len() as u64) as usize],
        kind: [
            SideKind::Wall,
            SideKind::Outer,
            SideKind::Interface,
            SideKind::Periodic,
        ][(rng.next_u64() % 4) as usize],
        circle: maybe(rng).then(|| signed(rng)),
        partner: maybe(rng).then(|| Partner {
            block: unsigned(rng),
            side: unsigned(rng),
            same_direction: maybe(rng),
        }),
        cgns: maybe(rng).then(|| Cgns1to1 {
            point_range: [
                [unsigned(rng), unsigned(rng)],
                [unsigned(rng), unsigned(rng)],
            ],
            point_range_donor: [
                [unsigned(rng), unsigned(rng)],
                [unsigned(rng), unsigned(rng)],
            ],
            transform: [signed(rng), signed(rng)],
        }),
        translation: maybe(rng)
            .then(|| [f64::from_bits(rng.next_u64()), (rng.next_f64() - 0.5) * 1e3]),
    }
}

#[test]
fn write_block_is_serde_json_on_random_blocks() {
    let mut rng = SplitMix64(8);
    let mut out = Vec::new();
    for _ in 0..20_000 {
        let b = BlockConnectivity {
            block: unsigned(&mut rng),
            dims: [unsigned(&mut rng), unsigned(&mut rng)],
            sides: [
                side(&mut rng),
                side(&mut rng),
                side(&mut rng),
                side(&mut rng),
            ],
        };
        out.clear();
        write_block(&mut out, &b);
        assert_eq!(
            String::from_utf8_lossy(&out),
            String::from_utf8_lossy(&serde_json::to_vec(&b).unwrap())
        );
    }
}
