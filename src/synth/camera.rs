//! Overhead pinhole camera with in-plane scene rotation, mirroring, small tilt and barrel
//! distortion.
//!
//! Coordinates: the shot is simulated in the impact frame (metres; origin at the cue ball's centre
//! at impact, `x` towards the object ball, `y = z × x`, `z` up; see `PHYSICS.md`). The scene is
//! placed on the table by `q = offset + Rot(rotation) · Mirror · p` (mirror: `y → -y`). The camera
//! sits `height_m` above the cloth, looking down; before tilt its frame is `X = q_x`, `Y = -q_y`,
//! `Z` = depth below the camera (`height_m - h` for a point `h` above the cloth), so an unmirrored
//! scene is seen as from above: the impact frame's `y` axis is `x` turned counter-clockwise on the
//! screen, and `rotation` is the on-screen counter-clockwise angle of `x` from the image's `+u`
//! axis. Tilt rotates the camera frame (`c = T · (X, Y, Z)`); normalised coordinates
//! `(c_x/c_z, c_y/c_z)` get barrel distortion `1 + k1 r²` (`k1 < 0`), then
//! `u = u0 + f x_d`, `v = v0 + f y_d` (pixels, `v` down).

use nalgebra::{Matrix3, Rotation3, Vector2, Vector3};

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub width: u32,
    pub height: u32,
    /// Focal length in pixels.
    pub f_px: f64,
    /// Height of the projection centre above the cloth (m).
    pub height_m: f64,
    /// Principal point (pixels).
    pub u0: f64,
    pub v0: f64,
    /// Camera tilt: rotation applied to level-camera coordinates.
    pub tilt: Matrix3<f64>,
    pub tilt_deg: f64,
    /// Radial distortion coefficient (negative: barrel).
    pub k1: f64,
    /// On-screen counter-clockwise angle of the impact frame's `x` axis (radians).
    pub rotation: f64,
    pub mirrored: bool,
    /// Impact point on the table relative to the point below the camera (m).
    pub offset: Vector2<f64>,
}

impl Camera {
    /// Level, undistorted camera `height_m` above the cloth with scale `px_per_mm` at cloth level.
    pub fn level(width: u32, height: u32, px_per_mm: f64, height_m: f64) -> Camera {
        Camera {
            width,
            height,
            f_px: px_per_mm * height_m * 1e3,
            height_m,
            u0: 0.5 * width as f64,
            v0: 0.5 * height as f64,
            tilt: Matrix3::identity(),
            tilt_deg: 0.0,
            k1: 0.0,
            rotation: 0.0,
            mirrored: false,
            offset: Vector2::zeros(),
        }
    }

    /// Tilts the camera by `deg` about the horizontal axis at on-table azimuth `azimuth` (rad).
    pub fn with_tilt(mut self, deg: f64, azimuth: f64) -> Camera {
        let axis = nalgebra::Unit::new_normalize(Vector3::new(azimuth.cos(), azimuth.sin(), 0.0));
        self.tilt = *Rotation3::from_axis_angle(&axis, deg.to_radians()).matrix();
        self.tilt_deg = deg;
        self
    }

    /// Impact-frame point (m) to table coordinates (m).
    pub fn to_table(&self, p: Vector2<f64>) -> Vector2<f64> {
        let y = if self.mirrored { -p.y } else { p.y };
        let (s, c) = self.rotation.sin_cos();
        self.offset + Vector2::new(c * p.x - s * y, s * p.x + c * y)
    }

    /// Image position (pixels) of a table point `q` (m) at height `h` (m) above the cloth.
    pub fn project_table(&self, q: Vector2<f64>, h: f64) -> Vector2<f64> {
        let c = self.tilt * Vector3::new(q.x, -q.y, self.height_m - h);
        let (xn, yn) = (c.x / c.z, c.y / c.z);
        let k = 1.0 + self.k1 * (xn * xn + yn * yn);
        Vector2::new(self.u0 + self.f_px * xn * k, self.v0 + self.f_px * yn * k)
    }

    /// Image position of an impact-frame point `p` (m) at height `h` above the cloth.
    pub fn project(&self, p: Vector2<f64>, h: f64) -> Vector2<f64> {
        self.project_table(self.to_table(p), h)
    }

    /// Local image scale (pixels per metre) at impact-frame point `p`, height `h`: the mean of
    /// the two axis scales, so a sphere of radius `R` centred there appears `R ×` this wide.
    pub fn scale_at(&self, p: Vector2<f64>, h: f64) -> f64 {
        let d = 1e-3;
        let c = self.project(p, h);
        let ex = (self.project(p + Vector2::new(d, 0.0), h) - c).norm();
        let ey = (self.project(p + Vector2::new(0.0, d), h) - c).norm();
        0.5 * (ex + ey) / d
    }

    /// Cloth-level scale in px/mm at impact-frame point `p` (what a ruler there would read).
    pub fn px_per_mm_at(&self, p: Vector2<f64>) -> f64 {
        self.scale_at(p, 0.0) * 1e-3
    }

    /// On-screen direction (unit, pixels) of an impact-frame direction at point `p`.
    pub fn direction_at(&self, p: Vector2<f64>, dir: Vector2<f64>, h: f64) -> Vector2<f64> {
        let d = 1e-3;
        (self.project(p + dir.normalize() * d, h) - self.project(p, h)).normalize()
    }

    pub fn contains(&self, px: Vector2<f64>, margin: f64) -> bool {
        px.x >= -margin
            && px.y >= -margin
            && px.x <= self.width as f64 + margin
            && px.y <= self.height as f64 + margin
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn perspective_enlarges_ball_centres() {
        let cam = Camera::level(2400, 1600, 3.5, 0.75);
        let r = 0.028575;
        let at_cloth = cam.scale_at(Vector2::zeros(), 0.0);
        let at_centre = cam.scale_at(Vector2::zeros(), r);
        // f/(H - R) over f/H = H/(H - R): 3.96 % larger for a billiard ball 75 cm below.
        assert!((at_centre / at_cloth - 0.75 / (0.75 - r)).abs() < 1e-9);
        assert!((cam.px_per_mm_at(Vector2::zeros()) - 3.5).abs() < 1e-9);
    }

    #[test]
    fn unmirrored_y_is_counter_clockwise_on_screen() {
        let mut cam = Camera::level(600, 400, 1.0, 0.75);
        cam.rotation = 30f64.to_radians();
        let x = cam.direction_at(Vector2::zeros(), Vector2::x(), 0.0);
        let y = cam.direction_at(Vector2::zeros(), Vector2::y(), 0.0);
        // Screen CCW angle uses -v as "up".
        let ang = |d: Vector2<f64>| (-d.y).atan2(d.x).to_degrees();
        assert!((ang(x) - 30.0).abs() < 1e-6);
        assert!((ang(y) - 120.0).abs() < 1e-6);
        cam.mirrored = true;
        let y = cam.direction_at(Vector2::zeros(), Vector2::y(), 0.0);
        assert!((ang(y) + 60.0).abs() < 1e-6);
    }
}
