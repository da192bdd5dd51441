//! The sweep store's atomic writes (`irtp_app::sweep::store`).

/// Threads writing one file at once (the parts of one point each
/// record its statepoint) all succeed, and the file is one whole write.
#[test]
fn concurrent_writers_of_one_file_all_succeed() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("signac_statepoint.json");
    std::thread::scope(|s| {
        for k in 0..8u8 {
            let path = &path;
            s.spawn(move || {
                for _ in 0..200 {
                    irtp_app::sweep::store::write_atomic(path, &[b'0' + k; 64]).unwrap();
                }
            });
        }
    });
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.len() == 64 && bytes.iter().all(|&b| b == bytes[0]));
}
