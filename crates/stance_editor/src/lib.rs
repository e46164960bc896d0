//! stance_editor
