//! Picking: which capsule a ray from the eye through the cursor hits first.

use glam::Vec3;

use crate::Capsule;

/// The first capsule along a ray and where the ray enters it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CapsuleHit {
    /// Index into the capsules that were tested.
    pub index: usize,
    /// Distance along the ray to the entry point (m).
    pub distance_m: f32,
    /// The entry point on the capsule's surface (world).
    pub point_world: Vec3,
}

/// The nearest capsule hit by the ray `origin_world + t * direction_world` (t >= 0), if any.
/// `direction_world` need not be normalised; degenerate rays hit nothing.
pub fn pick_capsule(
    capsules: &[Capsule],
    origin_world: Vec3,
    direction_world: Vec3,
) -> Option<CapsuleHit> {
    let direction = direction_world.try_normalize()?;
    if !origin_world.is_finite() {
        return None;
    }
    let mut best: Option<CapsuleHit> = None;
    for (index, capsule) in capsules.iter().enumerate() {
        let Some(distance_m) = ray_capsule_distance(origin_world, direction, capsule) else {
            continue;
        };
        if best.is_none_or(|hit| distance_m < hit.distance_m) {
            best = Some(CapsuleHit {
                index,
                distance_m,
                point_world: origin_world + direction * distance_m,
            });
        }
    }
    best
}

/// Distance along a unit ray to the surface of a capsule (its segment swept by a sphere).
pub(crate) fn ray_capsule_distance(
    origin: Vec3,
    direction: Vec3,
    capsule: &Capsule,
) -> Option<f32> {
    let radius = capsule.radius_m;
    if radius.is_nan() || radius <= 0.0 {
        return None;
    }
    let axis = capsule.end_world - capsule.start_world;
    let axis_length = axis.length();
    let mut nearest: Option<f32> = None;
    let mut consider = |t: f32| {
        if t >= 0.0 && t.is_finite() && nearest.is_none_or(|n| t < n) {
            nearest = Some(t);
        }
    };
    // The cylinder between the two caps.
    if axis_length > 1e-6 {
        let axis_unit = axis / axis_length;
        let offset = origin - capsule.start_world;
        let direction_across = direction - axis_unit * direction.dot(axis_unit);
        let offset_across = offset - axis_unit * offset.dot(axis_unit);
        let a = direction_across.length_squared();
        let b = 2.0 * direction_across.dot(offset_across);
        let c = offset_across.length_squared() - radius * radius;
        let discriminant = b * b - 4.0 * a * c;
        if a > 1e-12 && discriminant >= 0.0 {
            let root = discriminant.sqrt();
            for t in [(-b - root) / (2.0 * a), (-b + root) / (2.0 * a)] {
                let along = (offset + direction * t).dot(axis_unit);
                if (0.0..=axis_length).contains(&along) {
                    consider(t);
                }
            }
        }
    }
    // The two hemispherical caps.
    for centre in [capsule.start_world, capsule.end_world] {
        let offset = origin - centre;
        let b = offset.dot(direction);
        let c = offset.length_squared() - radius * radius;
        let discriminant = b * b - c;
        if discriminant >= 0.0 {
            let root = discriminant.sqrt();
            consider(-b - root);
            if c < 0.0 {
                // The eye is inside the sphere: the ray leaves it in front.
                consider(-b + root);
            }
        }
    }
    nearest
}

#[cfg(test)]
mod tests {
    use super::*;

    fn capsule(start: Vec3, end: Vec3, radius_m: f32) -> Capsule {
        Capsule {
            start_world: start,
            end_world: end,
            radius_m,
            color_linear: [1.0; 4],
        }
    }

    #[test]
    fn the_nearest_of_two_capsules_on_the_ray_is_picked_at_its_surface() {
        let capsules = [
            capsule(Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 1.0, -2.0), 0.1),
            capsule(Vec3::new(0.0, 0.0, -1.0), Vec3::new(0.0, 1.0, -1.0), 0.1),
        ];
        let hit = pick_capsule(&capsules, Vec3::new(0.0, 0.5, 0.0), -Vec3::Z).unwrap();
        assert_eq!(hit.index, 1);
        assert!((hit.distance_m - 0.9).abs() < 1e-5, "{}", hit.distance_m);
        assert!((hit.point_world - Vec3::new(0.0, 0.5, -0.9)).length() < 1e-5);
    }

    #[test]
    fn a_ray_past_the_end_hits_the_cap_and_a_ray_beside_misses() {
        let capsules = [capsule(Vec3::ZERO, Vec3::Y, 0.1)];
        let cap = pick_capsule(&capsules, Vec3::new(0.0, 1.05, 1.0), -Vec3::Z).unwrap();
        assert!(cap.distance_m > 0.9 && cap.distance_m < 1.0);
        assert!(pick_capsule(&capsules, Vec3::new(0.0, 1.2, 1.0), -Vec3::Z).is_none());
        assert!(pick_capsule(&capsules, Vec3::new(0.2, 0.5, 1.0), -Vec3::Z).is_none());
        // Behind the eye: nothing.
        assert!(pick_capsule(&capsules, Vec3::new(0.0, 0.5, 1.0), Vec3::Z).is_none());
    }

    #[test]
    fn degenerate_rays_and_capsules_hit_nothing_and_do_not_panic() {
        let capsules = [
            capsule(Vec3::ZERO, Vec3::ZERO, 0.1),
            capsule(Vec3::ZERO, Vec3::Y, f32::NAN),
        ];
        assert!(pick_capsule(&capsules, Vec3::new(0.0, 0.0, 1.0), Vec3::ZERO).is_none());
        assert!(pick_capsule(&capsules, Vec3::splat(f32::NAN), -Vec3::Z).is_none());
        let sphere = pick_capsule(&capsules, Vec3::new(0.0, 0.0, 1.0), -Vec3::Z).unwrap();
        assert_eq!(sphere.index, 0);
    }
}
