//! Albedo tables (spec closures.md §3.17): every blob decodes, its header records the
//! generator version and its sample count (512², 128² for the anisotropic tables); a seeded
//! random sample of 64 entries regenerated with the generator's f64 quadrature matches to
//! 1e-6; each `Eavg` table is the average of its parent; lookups interpolate linearly; the
//! anisotropic tables' azimuth interpolation goes through its nodes, and the symmetry it
//! relies on holds in the tables.

use vstructc::interp::tables::{self, N, TableId};
use vstructc_testkit::lutgen::{self, GENERATOR_VERSION};
use vstructc_testkit::verify::Rng;

#[test]
fn blobs_decode_with_expected_headers() {
    for id in TableId::ALL {
        let lut = tables::lut(id);
        assert_eq!(lut.data.len(), id.len(), "{}", id.name());
        assert_eq!(lut.generator_version, GENERATOR_VERSION, "{}", id.name());
        let g = lutgen::grid(id);
        assert_eq!(lut.samples_per_entry as usize, g * g, "{}", id.name());
        assert!(
            lut.data.iter().all(|v| v.is_finite() && *v >= 0.0),
            "{}",
            id.name()
        );
    }
}

#[test]
fn corrupt_blobs_are_rejected() {
    let id = TableId::E1Hc;
    let mut bytes = tables::blob(id).to_vec();
    assert!(tables::decode(id, &bytes).is_ok());
    bytes[200] ^= 1;
    assert_eq!(
        tables::decode(id, &bytes).unwrap_err(),
        tables::LutError::BadChecksum("e1_hc")
    );
    assert!(tables::decode(id, &bytes[..50]).is_err());
    assert!(tables::decode(TableId::SqHc, tables::blob(id)).is_err());
}

#[test]
fn random_entries_regenerate_exactly() {
    let primary: Vec<TableId> = TableId::ALL
        .iter()
        .copied()
        .filter(|t| t.eavg_parent().is_none())
        .collect();
    let mut rng = Rng::new(0x5EED);
    for _ in 0..64 {
        let id = primary[(rng.next_u64() % primary.len() as u64) as usize];
        let dims = id.dims();
        let idx = [0, 1, 2].map(|k| (rng.next_u64() % dims[k] as u64) as usize);
        let stored = f64::from(tables::lut(id).data[idx[0] + N * (idx[1] + N * idx[2])]);
        let fresh = lutgen::compute_entry(id, idx);
        assert!(
            (stored - fresh).abs() <= 1e-6 * stored.abs().max(1.0),
            "{} {idx:?}: stored {stored} regenerated {fresh}",
            id.name()
        );
    }
}

#[test]
fn eavg_tables_average_their_parents() {
    for id in TableId::ALL {
        let Some(parent) = id.eavg_parent() else {
            continue;
        };
        let want = lutgen::eavg_from(&tables::lut(parent).data);
        assert_eq!(want, tables::lut(id).data, "{}", id.name());
    }
}

#[test]
fn lookups_hit_nodes_and_interpolate() {
    let d = &tables::lut(TableId::E1Hc).data;
    // Node (μ = 10/31, √α = 20/31).
    let node = tables::lookup2(TableId::E1Hc, 10.0 / 31.0, 20.0 / 31.0);
    assert!((node - d[20 * N + 10]).abs() < 1e-6);
    let mid = tables::lookup2(TableId::E1Hc, 10.5 / 31.0, 20.0 / 31.0);
    assert!((mid - 0.5 * (d[20 * N + 10] + d[20 * N + 11])).abs() < 1e-6);
    // Clamping outside the axis ranges.
    assert_eq!(tables::lookup2(TableId::E1Hc, 2.0, 2.0), d[N * N - 1]);
    assert_eq!(tables::lookup2(TableId::E1Hc, -1.0, f32::NAN), d[0]);
}

/// The anisotropic albedo's azimuth interpolation (`tables::aniso_albedo`) goes through the
/// five tabulated azimuths `kπ/8` (at `x = cos 2φ = cos(kπ/4)`) and keeps a constant.
#[test]
fn azimuth_interpolation_hits_its_nodes() {
    let e = [0.9, 0.7, 0.45, 0.3, 0.1];
    for (k, want) in e.iter().enumerate() {
        let x = (k as f32 * std::f32::consts::FRAC_PI_4).cos();
        let got = tables::azimuth_interpolate(e, x);
        assert!((got - want).abs() < 1e-6, "node {k}: {got} vs {want}");
    }
    for x in [-1.0, -0.3, 0.0, 0.55, 1.0] {
        assert!((tables::azimuth_interpolate([0.4; 5], x) - 0.4).abs() < 1e-6);
    }
}

/// The interpolation reads the 22.5° tables with the widths swapped for 67.5°, which assumes
/// the albedo is unchanged when the view is mirrored across the diagonal and the widths
/// swapped: the 45° tables, their own mirror image, must then be symmetric in their widths.
#[test]
fn diagonal_tables_are_symmetric_in_their_widths() {
    for id in [
        TableId::E1HcAniso45,
        TableId::E1SepAniso45,
        TableId::WardClassicAniso45,
        TableId::WardGmAniso45,
    ] {
        let d = &tables::lut(id).data;
        for mu in [3, 17, 31] {
            for (j, k) in [(2, 29), (5, 11), (20, 30)] {
                let (a, b) = (d[mu + N * (j + N * k)], d[mu + N * (k + N * j)]);
                assert!(
                    (a - b).abs() <= 1e-5 * a.abs().max(1e-3),
                    "{} μ {mu} ({j}, {k}): {a} vs {b}",
                    id.name()
                );
            }
        }
    }
}
