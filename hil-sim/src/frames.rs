//! Owned by the data-side work (issue 4); being written.
