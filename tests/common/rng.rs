//! The tests' seeded PRNG is the simulator's (xorshift64*), so random tests
//! are repeatable and there is one generator in the project.

pub use paperbot::sim::noise::Rng;

/// A random pose in the team's box with the whole body (wheels, skid,
/// lidars) inside it (`sim::robot::body_fits` with the lab's realism).
pub fn random_pose_in_box(rng: &mut Rng) -> paperbot::sim::body::PoseF64 {
    use paperbot::sim::{arena::Arena, body::PoseF64, realism::Realism, robot::body_fits};
    let a = Arena::default();
    loop {
        let p = PoseF64::new(
            rng.range_f64(0.0, a.length_x_mm()),
            rng.range_f64(0.0, a.width_y_mm()),
            rng.range_f64(0.0, std::f64::consts::TAU),
        );
        if body_fits(&a, &Realism::LAB, &p) {
            return p;
        }
    }
}
