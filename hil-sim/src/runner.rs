//! Owned by the HIL work (issue 6); being written.
