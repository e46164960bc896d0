//! The 3D viewport: camera gestures from mouse, touch and pen, and the GPU texture that
//! [`stance_render`] draws into and egui shows.

use egui::{PointerButton, Response, Ui};
use glam::Vec2;
use stance_render::{OrbitCamera, RenderTarget, Scene, SceneRenderer};

/// What the user asked the camera to do this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraGesture {
    /// Turn around the target by a drag of this many screen points (x: yaw, y: pitch).
    Orbit(Vec2),
    /// Move the target so that the point under the pointer follows a drag of this many
    /// screen points.
    Pan(Vec2),
    /// Come closer by this factor (above 1) or go away (below 1).
    Zoom(f32),
    /// Frame the body again, seen from the front.
    Reset,
}

/// The input the viewport reads in one frame, extracted from egui so that the mapping from
/// gestures to camera moves can be tested without a window.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ViewportInput {
    /// How far the pointer was dragged over the viewport this frame (screen points, y down).
    pub drag_delta_px: Vec2,
    /// Whether the drag is with the primary (left) button, or one finger.
    pub primary_dragged: bool,
    /// Whether the drag is with the secondary (right) or the middle button.
    pub secondary_or_middle_dragged: bool,
    /// Whether Shift is held.
    pub shift_held: bool,
    /// Vertical wheel scroll over the viewport this frame (screen points; 0 elsewhere).
    pub scroll_px: f32,
    /// Pinch or Ctrl+wheel zoom over the viewport this frame (1 for none).
    pub zoom_factor: f32,
    /// Fingers on the screen (0 without a multi-touch gesture).
    pub touch_count: usize,
    /// How far the fingers moved together this frame (screen points).
    pub touch_translation_px: Vec2,
    /// Whether the viewport was double-clicked.
    pub double_clicked: bool,
}

impl ViewportInput {
    /// Reads the viewport's response and the frame's input.
    pub fn read(ui: &Ui, response: &Response) -> Self {
        // Everything that asks the response goes first: `Response` methods lock the egui
        // context themselves, and locking it again inside `ui.input` deadlocks (on the web,
        // parking_lot panics with "Parking not supported on this platform").
        let delta = response.drag_delta();
        let hovered = response.hovered() || response.dragged();
        let primary_dragged = response.dragged_by(PointerButton::Primary);
        let secondary_or_middle_dragged = response.dragged_by(PointerButton::Secondary)
            || response.dragged_by(PointerButton::Middle);
        let double_clicked = response.double_clicked();
        ui.input(|input| {
            let multi_touch = input.multi_touch();
            Self {
                drag_delta_px: Vec2::new(delta.x, delta.y),
                primary_dragged,
                secondary_or_middle_dragged,
                shift_held: input.modifiers.shift,
                scroll_px: if hovered {
                    input.smooth_scroll_delta.y
                } else {
                    0.0
                },
                zoom_factor: if hovered { input.zoom_delta() } else { 1.0 },
                touch_count: multi_touch.map_or(0, |touch| touch.num_touches),
                touch_translation_px: multi_touch.map_or(Vec2::ZERO, |touch| {
                    Vec2::new(touch.translation_delta.x, touch.translation_delta.y)
                }),
                double_clicked,
            }
        })
    }

    /// The camera gestures this input means. One finger or the left button orbits; two
    /// fingers pan and pinch; the right or middle button, or Shift with the left, pans;
    /// the wheel zooms; a double click frames the body again.
    pub fn gestures(&self) -> Vec<CameraGesture> {
        let mut gestures = Vec::new();
        if self.double_clicked {
            gestures.push(CameraGesture::Reset);
            return gestures;
        }
        if self.touch_count >= 2 {
            if self.touch_translation_px != Vec2::ZERO {
                gestures.push(CameraGesture::Pan(self.touch_translation_px));
            }
        } else if self.drag_delta_px != Vec2::ZERO {
            if self.secondary_or_middle_dragged || (self.primary_dragged && self.shift_held) {
                gestures.push(CameraGesture::Pan(self.drag_delta_px));
            } else if self.primary_dragged {
                gestures.push(CameraGesture::Orbit(self.drag_delta_px));
            }
        }
        let mut zoom = if self.zoom_factor.is_finite() && self.zoom_factor > 0.0 {
            self.zoom_factor
        } else {
            1.0
        };
        if self.scroll_px != 0.0 && self.scroll_px.is_finite() {
            zoom *= (self.scroll_px * 0.002).exp();
        }
        if (zoom - 1.0).abs() > 1e-6 {
            gestures.push(CameraGesture::Zoom(zoom));
        }
        gestures
    }
}

/// Applies gestures to the camera; returns whether anything changed.
pub(crate) fn apply_gestures(
    camera: &mut OrbitCamera,
    gestures: &[CameraGesture],
    viewport_height_px: f32,
) -> bool {
    for gesture in gestures {
        match *gesture {
            CameraGesture::Orbit(delta) => camera.orbit(delta),
            CameraGesture::Pan(delta) => camera.pan(delta, viewport_height_px),
            CameraGesture::Zoom(factor) => camera.zoom(factor),
            CameraGesture::Reset => {
                *camera = OrbitCamera {
                    orthographic: camera.orthographic,
                    ..OrbitCamera::default()
                }
            }
        }
    }
    !gestures.is_empty()
}

/// The renderer and its target texture, registered with egui.
pub(crate) struct ViewportRenderer {
    scene_renderer: SceneRenderer,
    target: Option<(RenderTarget, egui::TextureId)>,
}

impl ViewportRenderer {
    pub(crate) fn new(device: &wgpu::Device) -> Self {
        Self {
            scene_renderer: SceneRenderer::new(device),
            target: None,
        }
    }

    /// The scene renderer (images are drawn with it: it holds the characters' models).
    pub(crate) fn scene_renderer_mut(&mut self) -> &mut SceneRenderer {
        &mut self.scene_renderer
    }

    /// The scene renderer, to read which models it holds.
    pub(crate) fn scene_renderer(&self) -> &SceneRenderer {
        &self.scene_renderer
    }

    /// One step of the avatar's upload: true once it is complete.
    pub(crate) fn continue_avatar_upload(&mut self, render_state: &egui_wgpu::RenderState) -> bool {
        self.scene_renderer
            .continue_avatar_upload(&render_state.device, &render_state.queue)
    }

    /// Whether an avatar upload is under way.
    pub(crate) fn is_uploading_avatar(&self) -> bool {
        self.scene_renderer.is_uploading_avatar()
    }

    /// Renders the scene at `size_px` and returns the egui texture that shows it.
    pub(crate) fn render(
        &mut self,
        render_state: &egui_wgpu::RenderState,
        size_px: [u32; 2],
        camera: &OrbitCamera,
        scene: &Scene,
    ) -> egui::TextureId {
        let device = &render_state.device;
        let needs_new_target = self
            .target
            .as_ref()
            .is_none_or(|(target, _)| target.size_px() != size_px);
        if needs_new_target {
            let target = RenderTarget::new(device, size_px);
            let mut egui_renderer = render_state.renderer.write();
            let texture_id = match self.target.take() {
                Some((_, texture_id)) => {
                    egui_renderer.update_egui_texture_from_wgpu_texture(
                        device,
                        target.color_view(),
                        wgpu::FilterMode::Linear,
                        texture_id,
                    );
                    texture_id
                }
                None => egui_renderer.register_native_texture(
                    device,
                    target.color_view(),
                    wgpu::FilterMode::Linear,
                ),
            };
            self.target = Some((target, texture_id));
        }
        match &self.target {
            Some((target, texture_id)) => {
                self.scene_renderer
                    .render(device, &render_state.queue, target, camera, scene);
                *texture_id
            }
            None => egui::TextureId::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_drag_orbits_and_shift_left_drag_pans() {
        let drag = ViewportInput {
            drag_delta_px: Vec2::new(10.0, 0.0),
            primary_dragged: true,
            zoom_factor: 1.0,
            ..Default::default()
        };
        assert_eq!(
            drag.gestures(),
            vec![CameraGesture::Orbit(Vec2::new(10.0, 0.0))]
        );
        let shifted = ViewportInput {
            shift_held: true,
            ..drag
        };
        assert_eq!(
            shifted.gestures(),
            vec![CameraGesture::Pan(Vec2::new(10.0, 0.0))]
        );
    }

    #[test]
    fn two_fingers_pan_and_pinch_zooms() {
        let input = ViewportInput {
            touch_count: 2,
            touch_translation_px: Vec2::new(3.0, 4.0),
            zoom_factor: 1.25,
            drag_delta_px: Vec2::new(3.0, 4.0),
            primary_dragged: true,
            ..Default::default()
        };
        assert_eq!(
            input.gestures(),
            vec![
                CameraGesture::Pan(Vec2::new(3.0, 4.0)),
                CameraGesture::Zoom(1.25)
            ]
        );
    }

    #[test]
    fn wheel_up_zooms_in_and_bad_zoom_factors_are_ignored() {
        let input = ViewportInput {
            scroll_px: 100.0,
            zoom_factor: f32::NAN,
            ..Default::default()
        };
        let mut camera = OrbitCamera::default();
        let before = camera.distance_m;
        assert!(apply_gestures(&mut camera, &input.gestures(), 600.0));
        assert!(camera.distance_m < before);
    }

    #[test]
    fn double_click_frames_the_body_again() {
        let mut camera = OrbitCamera::default();
        camera.orbit(Vec2::new(300.0, 50.0));
        let input = ViewportInput {
            double_clicked: true,
            ..Default::default()
        };
        apply_gestures(&mut camera, &input.gestures(), 600.0);
        assert_eq!(camera, OrbitCamera::default());
    }
}
