//! SLURM arrays of a sweep (`irtp_app::sweep::slurm`): splitting, bundling
//! and resubmitting.

use irtp_app::sweep::slurm::{arrays, layout, tasks_of, SlurmOptions};
use std::path::PathBuf;

fn options(max_array: u64) -> SlurmOptions {
    SlurmOptions {
        partition: None,
        time: None,
        cpus_per_task: 1,
        max_array,
        max_tasks: 10_000,
        points_per_task: None,
        throttle: 100,
        retry_failed: false,
        exe: PathBuf::from("irtp"),
    }
}

/// 2500 points on a cluster with MaxArraySize 1001: one point per task,
/// three arrays (1001, 1001, 498), every task in exactly one of them.
#[test]
fn a_plan_larger_than_max_array_size_is_split() {
    let l = layout(2500, &options(1001)).unwrap();
    assert_eq!((l.tasks, l.points_per_task), (2500, 1));
    let a = arrays(&l, None);
    let shape: Vec<(u64, &str, u64)> = a
        .iter()
        .map(|s| (s.offset, s.indices.as_str(), s.count))
        .collect();
    assert_eq!(
        shape,
        [
            (0, "0-1000", 1001),
            (1001, "0-1000", 1001),
            (2002, "0-497", 498)
        ]
    );
    let mut seen = vec![0u8; 2500];
    for s in &a {
        for i in 0..s.count {
            seen[(s.offset + i) as usize] += 1;
        }
    }
    assert!(seen.iter().all(|&n| n == 1));
}

/// Beyond --max-tasks points are bundled: 10^6 points, 100 per task.
#[test]
fn huge_plans_bundle_points() {
    let l = layout(1_000_000, &options(1001)).unwrap();
    assert_eq!((l.tasks, l.points_per_task), (10_000, 100));
    assert_eq!(arrays(&l, None).len(), 10);
    let mut o = options(1001);
    o.points_per_task = Some(10);
    let e = layout(1_000_000, &o).unwrap_err().to_string();
    assert!(e.contains("points_per_task >= 100"), "{e}");
}

/// A resubmission lists only the tasks holding pending items, as
/// SLURM index ranges relative to each array.
#[test]
fn a_resubmission_lists_only_the_pending_tasks() {
    let mut o = options(10);
    o.points_per_task = Some(2);
    let l = layout(50, &o).unwrap();
    assert_eq!(l.tasks, 25);
    // Items 3 and 28 are in task 3; items 11, 12, 13 in tasks 11-13;
    // item 49 in task 24.
    let t = tasks_of(&l, &[3, 28, 11, 12, 13, 49]);
    assert_eq!(t, [3, 11, 12, 13, 24]);
    let a = arrays(&l, Some(&t));
    let shape: Vec<(u64, &str)> = a.iter().map(|s| (s.offset, s.indices.as_str())).collect();
    assert_eq!(shape, [(0, "3"), (10, "1-3"), (20, "4")]);
}
