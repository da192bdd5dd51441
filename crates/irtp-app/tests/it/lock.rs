//! Lock files (`irtp_app::lock`): one holder at a time, stale files taken.

use irtp_app::lock::{Acquired, FileLock};
use std::fs;

#[test]
fn a_second_holder_is_refused_and_the_file_goes_with_the_first() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("x.lock");
    let Acquired::Mine(first) = FileLock::try_acquire(&p).unwrap() else {
        panic!("free lock not acquired")
    };
    match FileLock::try_acquire(&p).unwrap() {
        Acquired::Held(who) => assert!(who.contains(&std::process::id().to_string()), "{who}"),
        Acquired::Mine(_) => panic!("lock taken twice"),
    }
    drop(first);
    assert!(!p.exists());
    assert!(matches!(
        FileLock::try_acquire(&p).unwrap(),
        Acquired::Mine(_)
    ));
}

#[test]
fn a_leftover_lock_file_of_a_dead_process_is_taken() {
    let tmp = tempfile::tempdir().unwrap();
    let p = tmp.path().join("y.lock");
    fs::write(&p, "otherhost 999999\n").unwrap();
    assert!(matches!(
        FileLock::try_acquire(&p).unwrap(),
        Acquired::Mine(_)
    ));
}
