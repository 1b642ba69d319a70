//! Subdivision options, named after OpenSubdiv's `Sdc::Options`.
//!
//! The defaults are the ones OpenSubdiv's reference data in `../shared/reference/opensubdiv` was
//! produced with (edge-only boundaries, uniform creasing, the Catmark triangle rule, smooth
//! face-varying data), which are also what an artist expects from Maya or RenderMan. Note that
//! `Sdc::Options()` itself defaults to `VTX_BOUNDARY_NONE` and `FVAR_LINEAR_ALL`; we do not.

/// How boundary vertices are interpolated (`Sdc::Options::VtxBoundaryInterpolation`).
///
/// Boundary edges are always infinitely sharp; the modes differ in what happens at the vertices.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BoundaryInterpolation {
    /// `VTX_BOUNDARY_NONE`: faces touching an unsharpened boundary become holes; the boundary
    /// vertices still support the interior surface.
    None,
    /// `VTX_BOUNDARY_EDGE_ONLY`: boundaries are smooth B-spline curves, corners are not
    /// interpolated.
    #[default]
    EdgeOnly,
    /// `VTX_BOUNDARY_EDGE_AND_CORNER`: as edge-only, and vertices with one face and two edges are
    /// infinitely sharp corners.
    EdgeAndCorner,
}

/// How semi-sharp edge sharpness decays from level to level (`Sdc::Options::CreasingMethod`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CreaseMethod {
    /// `CREASE_UNIFORM`: every sharpness drops by one per level.
    #[default]
    Uniform,
    /// `CREASE_CHAIKIN`: child edge sharpness averages with the neighbouring semi-sharp edges
    /// (DeRose, Kass & Truong 1998, section 3.3).
    Chaikin,
}

/// The edge rule next to triangles (`Sdc::Options::TriangleSubdivision`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TriangleRule {
    /// `TRI_SUB_CATMARK`: the plain Catmull-Clark edge rule.
    #[default]
    Catmark,
    /// `TRI_SUB_SMOOTH`: a modified edge weight next to triangles (Loop-like smoothness).
    Smooth,
}

/// How face-varying data (UVs) is interpolated (`Sdc::Options::FVarLinearInterpolation`), from
/// the smoothest to the most linear.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FVarLinear {
    /// `FVAR_LINEAR_NONE`: smooth everywhere; seams behave like smooth boundaries.
    #[default]
    None,
    /// `FVAR_LINEAR_CORNERS_ONLY`: face-varying corners are pinned.
    CornersOnly,
    /// `FVAR_LINEAR_CORNERS_PLUS1`: also junctions of three or more face-varying regions.
    CornersPlus1,
    /// `FVAR_LINEAR_CORNERS_PLUS2`: also darts and concave corners.
    CornersPlus2,
    /// `FVAR_LINEAR_BOUNDARIES`: linear along every face-varying boundary.
    Boundaries,
    /// `FVAR_LINEAR_ALL`: bilinear everywhere.
    All,
}

/// Every option that changes the subdivided surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Options {
    /// Boundary vertex interpolation.
    pub boundary: BoundaryInterpolation,
    /// Semi-sharp crease decay.
    pub crease_method: CreaseMethod,
    /// Edge rule next to triangles.
    pub triangle_rule: TriangleRule,
    /// Face-varying interpolation.
    pub fvar_linear: FVarLinear,
}

/// A name that does not spell any value of an option.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown {option} '{given}' (expected one of: {expected})")]
pub struct UnknownOption {
    /// Which option was being parsed.
    pub option: &'static str,
    /// What was given.
    pub given: String,
    /// The accepted spellings.
    pub expected: &'static str,
}

/// Names, as the command line and scene files spell them, in one table per option type.
macro_rules! named_option {
    ($ty:ty, $what:literal, [$(($variant:expr, $name:literal)),+ $(,)?]) => {
        impl $ty {
            /// Every value with its command-line name.
            pub const NAMES: &'static [($ty, &'static str)] = &[$(($variant, $name)),+];

            /// The command-line name of this value.
            #[must_use]
            pub fn name(self) -> &'static str {
                Self::NAMES.iter().find(|(v, _)| *v == self).map_or("", |(_, n)| n)
            }
        }

        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::std::str::FromStr for $ty {
            type Err = $crate::options::UnknownOption;

            fn from_str(s: &str) -> Result<Self, Self::Err> {
                Self::NAMES.iter().find(|(_, n)| *n == s).map(|(v, _)| *v).ok_or_else(|| {
                    $crate::options::UnknownOption {
                        option: $what,
                        given: s.to_owned(),
                        expected: concat!($($name, " "),+).trim_ascii_end(),
                    }
                })
            }
        }
    };
}

pub(crate) use named_option;

named_option!(
    BoundaryInterpolation,
    "boundary interpolation",
    [
        (BoundaryInterpolation::None, "none"),
        (BoundaryInterpolation::EdgeOnly, "edge-only"),
        (BoundaryInterpolation::EdgeAndCorner, "edge-and-corner"),
    ]
);
named_option!(
    CreaseMethod,
    "crease method",
    [
        (CreaseMethod::Uniform, "uniform"),
        (CreaseMethod::Chaikin, "chaikin")
    ]
);
named_option!(
    TriangleRule,
    "triangle rule",
    [
        (TriangleRule::Catmark, "catmark"),
        (TriangleRule::Smooth, "smooth")
    ]
);
named_option!(
    FVarLinear,
    "face-varying interpolation",
    [
        (FVarLinear::None, "none"),
        (FVarLinear::CornersOnly, "corners-only"),
        (FVarLinear::CornersPlus1, "corners-plus1"),
        (FVarLinear::CornersPlus2, "corners-plus2"),
        (FVarLinear::Boundaries, "boundaries"),
        (FVarLinear::All, "all"),
    ]
);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for &(v, n) in FVarLinear::NAMES {
            assert_eq!(n.parse::<FVarLinear>().unwrap(), v);
            assert_eq!(v.to_string(), n);
        }
        let err = "sharp".parse::<CreaseMethod>().unwrap_err();
        assert_eq!(
            err.to_string(),
            "unknown crease method 'sharp' (expected one of: uniform chaikin)"
        );
    }
}
