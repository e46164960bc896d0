//! stance_render
