//! Exports of a scene to other renderers: Mitsuba 3 (`mitsuba`), whose renders are the
//! references the evaluation compares against.

pub mod mitsuba;
