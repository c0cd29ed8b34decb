//! `aperture bench-rays` as a user runs it: the CSV has a row for every (quality, set, query,
//! mode, threads), the saved ray files hold 24 bytes a ray, a saved file timed again gives the
//! same answers, and a damaged ray file is an error naming it. Nothing here checks a timing.

mod common;

use common::{run_in as aperture, stderr, Scratch};
use std::collections::{BTreeSet, HashMap};

/// The CSV's rows as maps from column name to value.
fn parse_csv(csv: &str) -> Vec<HashMap<String, String>> {
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    lines
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            assert_eq!(cells.len(), header.len(), "{l}");
            header
                .iter()
                .zip(cells)
                .map(|(h, c)| (h.to_string(), c.to_string()))
                .collect()
        })
        .collect()
}

const SETS: [&str; 4] = ["primary_tile", "primary_random", "diffuse", "shadow"];

#[test]
fn bench_rays_writes_every_row_and_the_ray_files() {
    let dir = Scratch::new("bench-rays");
    let scene = common::demo_scene();
    let rows = run_generated_sets(&dir, &scene);
    assert_every_row_once(&rows);
    assert!(rows.iter().all(|r| r["scene"] == "demo.glb"));
    assert_ray_files_hold_every_ray(&dir, &rows);
    assert!(
        std::fs::metadata(dir.path("out/bench-rays.png"))
            .unwrap()
            .len()
            > 0
    );
    assert_saved_shadow_rays_give_the_same_answers(&dir, &scene, &rows);
}

/// Runs `bench-rays` on the generated sets of a 20x12 image with 3 lens samples, saving the
/// rays in `rays/`; the CSV's rows.
fn run_generated_sets(dir: &Scratch, scene: &std::path::Path) -> Vec<HashMap<String, String>> {
    let o = aperture(
        &[
            "bench-rays",
            scene.to_str().unwrap(),
            "--width",
            "20",
            "--height",
            "12",
            "--lens-samples",
            "3",
            "--repeats",
            "1",
            "--threads",
            "2",
            "-o",
            "out",
            "--save-rays",
            "rays",
        ],
        &dir.0,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("primary_random"));
    let csv = std::fs::read_to_string(dir.path("out/bench-rays.csv")).unwrap();
    parse_csv(&csv)
}

/// One row for every (quality, set, query, mode, threads), none twice.
fn assert_every_row_once(rows: &[HashMap<String, String>]) {
    let keys: BTreeSet<(String, String, String, String, String)> = rows
        .iter()
        .map(|r| {
            (
                r["quality"].clone(),
                r["set"].clone(),
                r["query"].clone(),
                r["mode"].clone(),
                r["threads"].clone(),
            )
        })
        .collect();
    assert_eq!(keys.len(), rows.len(), "no row twice");
    for q in ["fast", "medium", "high"] {
        for set in SETS {
            for query in ["closest", "occluded"] {
                for mode in ["one-ray", "batch", "packet"] {
                    for threads in ["1", "2"] {
                        let key = (q, set, query, mode, threads).map_into();
                        assert!(keys.contains(&key), "missing {key:?}");
                    }
                }
            }
        }
    }
    // quality × set × query × mode × threads
    assert_eq!(rows.len(), 3 * 4 * 2 * 3 * 2);
}

/// The primary sets hold every lens sample of every pixel, and each saved file 24 bytes a ray.
fn assert_ray_files_hold_every_ray(dir: &Scratch, rows: &[HashMap<String, String>]) {
    let rays_of = |set: &str| -> u64 {
        rows.iter().find(|r| r["set"] == set).unwrap()["rays"]
            .parse()
            .unwrap()
    };
    assert_eq!(rays_of("primary_tile"), 20 * 12 * 3);
    for set in SETS {
        let len = std::fs::metadata(dir.path(&format!("rays/{set}.rays")))
            .unwrap()
            .len();
        assert_eq!(len, 24 * rays_of(set), "{set}");
    }
}

/// The saved shadow rays timed again (with their tmax sidecar) give the same answers.
fn assert_saved_shadow_rays_give_the_same_answers(
    dir: &Scratch,
    scene: &std::path::Path,
    rows: &[HashMap<String, String>],
) {
    let o = aperture(
        &[
            "bench-rays",
            scene.to_str().unwrap(),
            "--rays",
            "rays/shadow.rays",
            "--no-generated",
            "--bvh-quality",
            "medium",
            "--repeats",
            "1",
            "--threads",
            "1",
            "-o",
            "again",
        ],
        &dir.0,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let again = parse_csv(&std::fs::read_to_string(dir.path("again/bench-rays.csv")).unwrap());
    assert_eq!(again.len(), 6, "2 queries × 3 modes × 1 thread");
    for r in &again {
        let first = rows
            .iter()
            .find(|f| {
                f["quality"] == "medium"
                    && f["set"] == "shadow"
                    && f["query"] == r["query"]
                    && f["mode"] == r["mode"]
                    && f["threads"] == "1"
            })
            .unwrap();
        assert_eq!((&r["rays"], &r["hits"]), (&first["rays"], &first["hits"]));
    }
}

#[test]
fn a_truncated_ray_file_is_an_error_naming_it() {
    let dir = Scratch::new("bench-rays-bad");
    std::fs::write(dir.path("cut.rays"), [0u8; 30]).unwrap();
    let scene = common::demo_scene();
    let o = aperture(
        &[
            "bench-rays",
            scene.to_str().unwrap(),
            "--rays",
            "cut.rays",
            "--no-generated",
        ],
        &dir.0,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("cut.rays"), "{}", stderr(&o));
    assert!(stderr(&o).contains("30 bytes"), "{}", stderr(&o));
}

#[test]
fn ray_sets_larger_than_memory_are_refused_before_allocating() {
    let dir = Scratch::new("bench-rays-huge");
    let scene = common::demo_scene();
    let o = aperture(
        &[
            "bench-rays",
            scene.to_str().unwrap(),
            "--width",
            "16384",
            "--height",
            "16384",
            "--lens-samples",
            "65536",
        ],
        &dir.0,
    );
    assert!(!o.status.success());
    assert!(stderr(&o).contains("lens samples needs"), "{}", stderr(&o));
}

trait MapInto {
    fn map_into(self) -> (String, String, String, String, String);
}

impl MapInto for (&str, &str, &str, &str, &str) {
    fn map_into(self) -> (String, String, String, String, String) {
        (
            self.0.into(),
            self.1.into(),
            self.2.into(),
            self.3.into(),
            self.4.into(),
        )
    }
}
