//! Scene files (placeholder; being written).
