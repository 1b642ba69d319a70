//! The mannequin's skeleton, its linear-blend skinning weights and its motion.
//!
//! Bones are segments between joints. A control vertex's weights fall off with its distance to
//! the segments of the bones its [`Part`] may follow (`w ∝ 1 / max(d, 1 cm)⁴`, normalized), so
//! joints bend smoothly and a hand never drags the hip. A pose is one rest-relative rigid
//! transform per bone, built down the hierarchy (pelvis → spine → chest → neck/head and
//! clavicle → upper arm → forearm; pelvis → thigh → shin); a vertex moves to
//! `p + Σ w_b (T_b p − p)`, which is exactly `p` in the rest pose.
//!
//! The motion (frames 0..=120 at 24 fps, frame 0 the rest A-pose): the arms raise to about
//! 16° above horizontal and lower to about 56° below it, elbows bending; the torso twists up to
//! ±20° about Y, spread over spine and chest, the head turning back half of it; the right foot
//! steps 40 cm forward (frames 24–60), then the left foot joins it (frames 66–102), the hips
//! following the mean of the feet and dipping while they are apart. The legs are posed by
//! two-bone inverse kinematics so the feet stay flat on the floor when planted.

use std::f64::consts::PI;

use nalgebra::{Isometry3, Translation3, UnitQuaternion};

use super::body::{Part, Side, arm_frame, leg_x};
use super::geom::{P, V};

/// Frames written, 0 (rest) to this one inclusive.
pub const LAST_FRAME: usize = 120;

/// The bones, in the order of [`Skeleton::segments`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Bone {
    Pelvis,
    Spine,
    Chest,
    Neck,
    Head,
    Clavicle(Side),
    UpperArm(Side),
    LowerArm(Side),
    UpperLeg(Side),
    LowerLeg(Side),
    Foot(Side),
}

const BONES: [Bone; 17] = [
    Bone::Pelvis,
    Bone::Spine,
    Bone::Chest,
    Bone::Neck,
    Bone::Head,
    Bone::Clavicle(Side::Left),
    Bone::Clavicle(Side::Right),
    Bone::UpperArm(Side::Left),
    Bone::UpperArm(Side::Right),
    Bone::LowerArm(Side::Left),
    Bone::LowerArm(Side::Right),
    Bone::UpperLeg(Side::Left),
    Bone::UpperLeg(Side::Right),
    Bone::LowerLeg(Side::Left),
    Bone::LowerLeg(Side::Right),
    Bone::Foot(Side::Left),
    Bone::Foot(Side::Right),
];

fn bone_index(b: Bone) -> usize {
    BONES.iter().position(|&x| x == b).expect("listed bone")
}

/// The bones a vertex of `part` may follow.
fn candidates(part: Part) -> Vec<Bone> {
    match part {
        Part::Torso => vec![
            Bone::Pelvis,
            Bone::Spine,
            Bone::Chest,
            Bone::Clavicle(Side::Left),
            Bone::Clavicle(Side::Right),
            Bone::UpperLeg(Side::Left),
            Bone::UpperLeg(Side::Right),
        ],
        Part::Head => vec![Bone::Chest, Bone::Neck, Bone::Head],
        Part::Arm(s) => vec![
            Bone::Chest,
            Bone::Clavicle(s),
            Bone::UpperArm(s),
            Bone::LowerArm(s),
        ],
        Part::Leg(s) => vec![
            Bone::Pelvis,
            Bone::UpperLeg(s),
            Bone::LowerLeg(s),
            Bone::Foot(s),
        ],
    }
}

/// Joint positions of one side.
#[derive(Clone, Copy)]
struct Limbs {
    sternoclavicular: P,
    shoulder: P,
    elbow: P,
    hand: P,
    arm: V,
    hip: P,
    knee: P,
    ankle: P,
    toe: P,
}

/// Joints in the body's final space.
pub struct Skeleton {
    pelvis: P,
    waist: P,
    chest: P,
    neck: P,
    head: P,
    crown: P,
    sides: [Limbs; 2],
}

impl Skeleton {
    /// The skeleton of the design-space body, mapped by `to_final`.
    pub fn new(to_final: impl Fn(P) -> P) -> Self {
        let f = &to_final;
        let sides = Side::BOTH.map(|side| {
            let (shoulder, d) = arm_frame(side);
            let x = leg_x(side);
            Limbs {
                sternoclavicular: f(P::new(0.03 * side.sign(), 1.40, 0.0)),
                shoulder: f(shoulder),
                elbow: f(shoulder + d * 0.29),
                hand: f(shoulder + d * 0.74),
                arm: d,
                hip: f(P::new(x, 0.86, 0.0)),
                knee: f(P::new(x, 0.47, 0.0)),
                ankle: f(P::new(x, 0.10, 0.0)),
                toe: f(P::new(x, 0.03, 0.17)),
            }
        });
        Self {
            pelvis: f(P::new(0.0, 0.86, 0.0)),
            waist: f(P::new(0.0, 1.00, 0.0)),
            chest: f(P::new(0.0, 1.16, 0.0)),
            neck: f(P::new(0.0, 1.42, 0.0)),
            head: f(P::new(0.0, 1.56, 0.0)),
            crown: f(P::new(0.0, 1.74, 0.0)),
            sides,
        }
    }

    fn limbs(&self, side: Side) -> &Limbs {
        &self.sides[usize::from(side == Side::Right)]
    }

    /// The rest segment of each bone.
    fn segment(&self, b: Bone) -> (P, P) {
        match b {
            Bone::Pelvis => (self.pelvis, self.waist),
            Bone::Spine => (self.waist, self.chest),
            Bone::Chest => (self.chest, self.neck),
            Bone::Neck => (self.neck, self.head),
            Bone::Head => (self.head, self.crown),
            Bone::Clavicle(s) => (self.limbs(s).sternoclavicular, self.limbs(s).shoulder),
            Bone::UpperArm(s) => (self.limbs(s).shoulder, self.limbs(s).elbow),
            Bone::LowerArm(s) => (self.limbs(s).elbow, self.limbs(s).hand),
            Bone::UpperLeg(s) => (self.limbs(s).hip, self.limbs(s).knee),
            Bone::LowerLeg(s) => (self.limbs(s).knee, self.limbs(s).ankle),
            Bone::Foot(s) => (self.limbs(s).ankle, self.limbs(s).toe),
        }
    }

    /// Normalized (bone, weight) pairs of a vertex at `p` of `part`.
    pub fn weights(&self, p: P, part: Part) -> Vec<(usize, f64)> {
        let raw: Vec<(usize, f64)> = candidates(part)
            .into_iter()
            .map(|b| {
                let (a, c) = self.segment(b);
                let d = segment_distance(p, a, c).max(0.01);
                (bone_index(b), d.powi(-4))
            })
            .collect();
        let total: f64 = raw.iter().map(|(_, w)| w).sum();
        raw.into_iter().map(|(b, w)| (b, w / total)).collect()
    }

    /// The rest-relative transform of every bone at `frame`.
    pub fn pose(&self, frame: usize) -> Vec<Isometry3<f64>> {
        let phase = 2.0 * PI * frame as f64 / LAST_FRAME as f64;
        let raise = (35f64 * phase.sin() + 10.0 * (1.0 - phase.cos())).to_radians();
        let elbow = (10.0 * (1.0 - phase.cos())).to_radians();
        let twist = 20f64.to_radians() * phase.sin();

        const STRIDE: f64 = 0.40;
        let step = |start: f64| smoothstep((frame as f64 - start) / 36.0);
        let feet = [step(66.0), step(24.0)].map(|u| (STRIDE * u, 0.07 * (PI * u).sin()));
        let hips_z = (feet[0].0 + feet[1].0) / 2.0;
        let apart = (feet[0].0 - feet[1].0).abs() / STRIDE;
        let dip = 0.05 * apart * apart;

        let mut world = vec![Isometry3::identity(); BONES.len()];
        let mut set = |b: Bone, iso: Isometry3<f64>| world[bone_index(b)] = iso;
        let pelvis = Isometry3::from_parts(
            Translation3::new(0.0, -dip, hips_z),
            UnitQuaternion::identity(),
        );
        let spine = pelvis * rotate_about(self.waist, V::y(), 0.4 * twist);
        let chest = spine * rotate_about(self.chest, V::y(), 0.6 * twist);
        let neck = chest * rotate_about(self.neck, V::y(), -0.5 * twist);
        set(Bone::Pelvis, pelvis);
        set(Bone::Spine, spine);
        set(Bone::Chest, chest);
        set(Bone::Neck, neck);
        set(Bone::Head, neck);
        for (side, &(foot_z, lift)) in Side::BOTH.iter().zip(&feet) {
            let l = self.limbs(*side);
            let s = side.sign();
            let clavicle = chest * rotate_about(l.sternoclavicular, V::z(), 0.3 * raise * s);
            let upper = clavicle * rotate_about(l.shoulder, V::z(), 0.7 * raise * s);
            let lower = upper * rotate_about(l.elbow, l.arm.cross(&V::z()), elbow);
            set(Bone::Clavicle(*side), clavicle);
            set(Bone::UpperArm(*side), upper);
            set(Bone::LowerArm(*side), lower);

            let target = l.ankle + V::new(0.0, lift, foot_z);
            let (hip_flex, knee_bend) = leg_ik(pelvis * l.hip, target, l);
            let thigh = pelvis * rotate_about(l.hip, V::x(), -hip_flex);
            let shin = thigh * rotate_about(l.knee, V::x(), knee_bend);
            set(Bone::UpperLeg(*side), thigh);
            set(Bone::LowerLeg(*side), shin);
            set(
                Bone::Foot(*side),
                Isometry3::from_parts(
                    Translation3::from(target - l.ankle),
                    UnitQuaternion::identity(),
                ),
            );
        }
        world
    }
}

/// Hip flexion (forward) and knee bend (backward) that put the ankle of a leg hanging from `hip`
/// at `target`, in the leg's sagittal plane (law of cosines; straight when out of reach).
fn leg_ik(hip: P, target: P, l: &Limbs) -> (f64, f64) {
    let (l1, l2) = ((l.knee - l.hip).norm(), (l.ankle - l.knee).norm());
    let to = target - hip;
    let d = to.norm().min(l1 + l2);
    let forward = to.z.atan2(-to.y);
    let acos = |c: f64| c.clamp(-1.0, 1.0).acos();
    let at_hip = acos((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d));
    let at_knee = acos((l1 * l1 + l2 * l2 - d * d) / (2.0 * l1 * l2));
    (forward + at_hip, PI - at_knee)
}

/// A rotation by `angle` about the axis through `p` along `axis`.
fn rotate_about(p: P, axis: V, angle: f64) -> Isometry3<f64> {
    let r = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_normalize(axis), angle);
    Isometry3::from_parts(Translation3::from(p.coords - r * p.coords), r)
}

/// 0 before 0, 1 after 1, a cubic ease between.
fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: P, a: P, b: P) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (p - (a + ab * t)).norm()
}

/// Moves `rest` by the blended transforms of `pose`.
pub fn skin(rest: &[P], weights: &[Vec<(usize, f64)>], pose: &[Isometry3<f64>]) -> Vec<P> {
    rest.iter()
        .zip(weights)
        .map(|(p, ws)| p + ws.iter().map(|&(b, w)| (pose[b] * p - p) * w).sum::<V>())
        .collect()
}
