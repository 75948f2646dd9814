//! Replays the committed fuzzing corpus of the lens reply decoder
//! (`fuzz/corpus/lens_reply/*`, the target `fuzz/fuzz_targets/lens_reply.rs`) with the
//! fuzz target's own checks, on stable: CI keeps every input fuzzing found interesting,
//! crashes included once fixed.

include!("../../../../fuzz/fuzz_targets/lens_reply_check.rs");

#[test]
fn the_lens_reply_corpus_decodes_without_a_panic_or_a_broken_contract() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/corpus/lens_reply");
    let mut inputs = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        check(&std::fs::read(&path).unwrap());
        inputs += 1;
    }
    assert!(inputs >= 70, "only {inputs} corpus inputs in {}", dir.display());
}
