//! stance_web
