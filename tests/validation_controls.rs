//! Negative controls of the validation check itself: a deliberate misuse must be reported,
//! or a broken messenger (or a check that reads the messages too early) would let every
//! other test pass. Each misuse runs on a context of its own, which the test destroys with
//! `finish` to read what its whole life left behind. GPU objects release themselves when
//! dropped, so a leak takes `mem::forget` or an object kept past `finish`.

mod common;

use common::transfer_buffer;
use voxgi::vk::vk;

#[test]
fn a_write_after_write_without_a_barrier_is_reported() {
    let ctx = common::raw_context();
    let target = transfer_buffer(&ctx, "hazard target");
    common::run_write_after_write(&ctx, &target);
    drop(target);
    let report = ctx.finish();
    assert!(report.leaked_allocations.is_empty(), "{report}");
    assert!(
        report
            .validation_messages
            .iter()
            .any(|m| m.contains("SYNC-HAZARD-WRITE-AFTER-WRITE")),
        "the hazard went unreported; messages: {:?}",
        report.validation_messages
    );
}

#[test]
fn objects_and_memory_never_freed_are_reported_at_teardown() {
    let ctx = common::raw_context();
    let forgotten = transfer_buffer(&ctx, "forgotten on purpose");
    let kept = forgotten.raw;
    // Nothing is wrong yet: a check made here (before teardown) sees nothing.
    assert_eq!(ctx.validation.total(), 0, "{:?}", ctx.validation.messages());
    std::mem::forget(forgotten);
    let report = ctx.finish();
    assert_eq!(
        report.leaked_allocations,
        ["forgotten on purpose"],
        "{report}"
    );
    // The layers name the buffer never destroyed when the device is destroyed.
    let handle = format!("{:x}", vk::Handle::as_raw(kept));
    assert!(
        report
            .validation_messages
            .iter()
            .any(|m| m.contains("VkBuffer") && m.to_lowercase().contains(&handle)),
        "the leaked VkBuffer 0x{handle} went unreported; messages: {:?}",
        report.validation_messages
    );
}

/// An object still alive when its context is finished is a leak, and dropping it afterwards
/// touches nothing of the destroyed device (no crash, no further message).
#[test]
fn an_object_kept_past_finish_is_reported_and_its_late_drop_is_harmless() {
    let ctx = common::raw_context();
    let kept = transfer_buffer(&ctx, "kept past finish");
    let report = ctx.finish();
    assert_eq!(report.leaked_allocations, ["kept past finish"], "{report}");
    assert!(
        report
            .validation_messages
            .iter()
            .any(|m| m.contains("VkBuffer")),
        "the buffer alive at vkDestroyDevice went unreported: {report}"
    );
    drop(kept);
}

#[test]
fn a_clean_context_reports_nothing_at_teardown() {
    let ctx = common::raw_context();
    let b = transfer_buffer(&ctx, "freed");
    drop(b);
    let report = ctx.finish();
    assert!(report.is_clean(), "{report}");
}

/// The fixture every other test uses fails a test that leaks, when its context drops.
#[test]
#[should_panic(expected = "1 leaked allocation(s) over the context's life")]
fn the_test_fixture_fails_a_test_that_leaks() {
    let ctx = common::context();
    std::mem::forget(transfer_buffer(&ctx, "leaked by the test"));
}
