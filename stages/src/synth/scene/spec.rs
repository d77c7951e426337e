//! `SceneSpec`: every knob of the procedural street scene, with the presets `tiny`, `demo` and
//! `paper_area(0..4)` (test areas in the spirit of thesis 5.5, Table 5-1).
//!
//! Frames: the scene is modelled in a *street-local* frame (metres): the main street runs along local +x
//! with its crown on local y = 0, local +y is to the left of +x, z is world height. Local → world is a
//! rotation by `street_heading_deg` about Z plus the offset `origin_world` (so no street is gifted as
//! being grid-aligned).

use super::epoch_changes::EpochChangeSpec;

/// Sun position: azimuth clockwise from grid north, elevation above the horizon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunSpec {
    pub azimuth_deg: f64,
    pub elevation_deg: f64,
}

/// A street crossing the main street at right angles (along local y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossStreetSpec {
    /// Local x of the cross street's crown line, m.
    pub at_x_m: f64,
    /// Half width of its carriageway (kerb to kerb / 2), m. Should not exceed the main street's.
    pub half_width_m: f64,
    /// Extent towards local −y (right of the main street's direction) from the main crown, m (0 = none: T-junction).
    pub extent_right_m: f64,
    /// Extent towards local +y (left), m (0 = none).
    pub extent_left_m: f64,
}

/// A canal along the right-hand (local −y) side of the main street.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CanalSpec {
    /// Width of the quay between the sidewalk's outer edge and the water, m.
    pub quay_width_m: f64,
    /// Width of the water, m.
    pub width_m: f64,
    /// Water surface below the quay, m.
    pub drop_m: f64,
}

/// The driving route (right-hand lane of the main street, optionally turning right at the junction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RouteSpec {
    /// Local x where the route starts, m.
    pub start_x_m: f64,
    /// Lateral offset of the lane centre to the right of the crown, m.
    pub lane_offset_m: f64,
    /// Turn right into the cross street (needs one with `extent_right_m > 0`); otherwise drive straight.
    pub turn_right: bool,
    /// Radius of the turn's arc, m.
    pub turn_radius_m: f64,
    /// Length driven after the junction (along the cross street when turning, else along the main street), m.
    pub length_after_junction_m: f64,
    /// Where a straight route ends (local x, m) when there is no turn.
    pub end_x_m: f64,
}

/// All knobs of the procedural street scene (see the module doc for the frames). Ranges `[lo, hi]` are
/// sampled uniformly per object by the seeded generator.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSpec {
    /// World XY of the local origin (RD-New-like, m).
    pub origin_world: [f64; 2],
    /// Direction of the main street's +x axis, counter-clockwise from world east, degrees.
    pub street_heading_deg: f64,
    /// Height of the main crown at the local origin (world Z, m).
    pub base_height_m: f64,
    /// Longitudinal slope along local x (dz/dx, e.g. 0.007 = 0.7 %).
    pub slope_x: f64,
    /// Slope along local y (dz/dy), i.e. along the cross street.
    pub slope_y: f64,
    /// Cross-fall from the crown to the kerbs (dz per m, e.g. 0.02 = 2 %).
    pub crossfall: f64,
    /// Kerb step height, m.
    pub kerb_height_m: f64,
    /// Width of the kerb stones' top band (part of the raised side), m.
    pub kerb_band_m: f64,
    /// Main street length along local x (from x = 0), m.
    pub street_length_m: f64,
    /// Half width of the main carriageway, m.
    pub road_half_width_m: f64,
    /// Width of the parking strip inside each kerb (0 = no parking), m.
    pub parking_width_m: f64,
    /// Sidewalk width (from the kerb), m.
    pub sidewalk_width_m: f64,
    pub cross_street: Option<CrossStreetSpec>,
    pub canal: Option<CanalSpec>,
    /// Paint road markings (centre/edge lines, zebras, stop lines, arrows).
    pub markings: bool,
    /// Spacing of manhole covers along each street (0 = none), m.
    pub manhole_spacing_m: f64,
    /// Buildings on the left (+y) / right (−y) side of the main street.
    pub buildings_left: bool,
    pub buildings_right: bool,
    /// Buildings along the cross street too.
    pub buildings_on_cross_street: bool,
    /// Building set-back behind the sidewalk's outer edge, m.
    pub setback_m: [f64; 2],
    /// Building frontage width, m.
    pub building_width_m: [f64; 2],
    /// Gap between neighbouring buildings, m (0 allowed).
    pub building_gap_m: [f64; 2],
    /// Building depth, m.
    pub building_depth_m: [f64; 2],
    /// Number of storeys.
    pub storeys: [u32; 2],
    /// Storey height, m.
    pub storey_height_m: [f64; 2],
    /// Probability of a gable roof (else flat).
    pub gable_probability: f64,
    /// Probability that a building has balconies/oriels on its upper floors (protruding up to 0.5 m).
    pub balcony_probability: f64,
    /// Tree spacing along each sidewalk (0 = no trees), m.
    pub tree_spacing_m: f64,
    /// Tree positions: offset of the trunk behind the kerb, m.
    pub tree_offset_m: f64,
    /// Crown horizontal radius, m.
    pub crown_radius_m: [f64; 2],
    /// Height of the crown centre above the ground, m.
    pub crown_centre_height_m: [f64; 2],
    /// Probability that a parking slot holds a car.
    pub car_probability: f64,
    /// Of the cars: fraction present in the mobile-mapping epoch only, and in the aerial epoch only.
    pub car_mm_only_fraction: f64,
    pub car_aerial_only_fraction: f64,
    pub route: RouteSpec,
    pub sun_mobile_mapping: SunSpec,
    pub sun_aerial: SunSpec,
    /// Differences between the epochs beyond sun and cars (markings, roadworks, grown crowns); `None` = none.
    pub changes: Option<EpochChangeSpec>,
}

impl SceneSpec {
    /// About 60 m of straight street ending at a T-junction, buildings on both sides: fast tests. The route (six
    /// panoramas, 20–45 m) runs between façades on both sides up to the junction approach, whose arrow, stop line
    /// and zebra crossing it sees along with dashes and manholes, so both the nadir chain (road markings) and the
    /// oblique chain (façades on both sides) have content to register.
    pub fn tiny() -> Self {
        Self {
            street_length_m: 60.0,
            cross_street: Some(CrossStreetSpec {
                at_x_m: 55.0,
                half_width_m: 4.0,
                extent_right_m: 0.0,
                extent_left_m: 20.0,
            }),
            manhole_spacing_m: 12.0,
            setback_m: [1.0, 1.0],
            building_width_m: [9.0, 13.0],
            building_gap_m: [0.0, 1.0],
            tree_spacing_m: 14.0,
            buildings_on_cross_street: false,
            route: RouteSpec {
                start_x_m: 20.0,
                lane_offset_m: 1.5,
                turn_right: false,
                turn_radius_m: 6.0,
                length_after_junction_m: 0.0,
                end_x_m: 47.0,
            },
            ..Self::demo()
        }
    }

    /// `tiny`'s street, straight and without a junction, long enough for a route of `route_length_m`.
    pub fn long_street(route_length_m: f64) -> Self {
        let tiny = Self::tiny();
        let route = RouteSpec {
            end_x_m: tiny.route.start_x_m + route_length_m,
            ..tiny.route
        };
        Self {
            street_length_m: route.end_x_m + 15.0,
            cross_street: None,
            route,
            ..tiny
        }
    }

    /// One ~200 m street with a junction (cross street); the route drives ~190 m in the right-hand lane and
    /// turns right at the junction (about 40 recordings at 5 m). Buildings on both sides.
    pub fn demo() -> Self {
        Self {
            origin_world: [92_000.0, 437_000.0],
            street_heading_deg: 23.0,
            base_height_m: 1.20,
            slope_x: 0.007,
            slope_y: -0.004,
            crossfall: 0.02,
            kerb_height_m: 0.12,
            kerb_band_m: 0.15,
            street_length_m: 200.0,
            road_half_width_m: 4.5,
            parking_width_m: 2.0,
            sidewalk_width_m: 3.0,
            cross_street: Some(CrossStreetSpec {
                at_x_m: 120.0,
                half_width_m: 4.0,
                extent_right_m: 90.0,
                extent_left_m: 60.0,
            }),
            canal: None,
            markings: true,
            manhole_spacing_m: 30.0,
            buildings_left: true,
            buildings_right: true,
            buildings_on_cross_street: true,
            setback_m: [0.0, 2.5],
            building_width_m: [8.0, 20.0],
            building_gap_m: [0.0, 6.0],
            building_depth_m: [9.0, 14.0],
            storeys: [3, 5],
            storey_height_m: [3.0, 3.5],
            gable_probability: 0.4,
            balcony_probability: 0.5,
            tree_spacing_m: 16.0,
            tree_offset_m: 1.2,
            crown_radius_m: [1.8, 2.8],
            crown_centre_height_m: [5.5, 7.0],
            car_probability: 0.6,
            car_mm_only_fraction: 0.2,
            car_aerial_only_fraction: 0.2,
            route: RouteSpec {
                start_x_m: 8.0,
                lane_offset_m: 1.5,
                turn_right: true,
                turn_radius_m: 6.0,
                length_after_junction_m: 80.0,
                end_x_m: 195.0,
            },
            sun_mobile_mapping: SunSpec {
                azimuth_deg: 140.0,
                elevation_deg: 38.0,
            },
            sun_aerial: SunSpec {
                azimuth_deg: 205.0,
                elevation_deg: 47.0,
            },
            changes: None,
        }
    }

    /// Test areas in the spirit of thesis 5.5 (Table 5-1, Figure 5.4): 0 open road with salient markings;
    /// 1 narrow road under trees; 2 a canal on one side and no road markings; 3 façades far away or hidden
    /// by trees. Indices beyond 3 are clamped to 3.
    pub fn paper_area(index: usize) -> Self {
        let demo = Self::demo();
        let straight = RouteSpec {
            start_x_m: 5.0,
            lane_offset_m: 1.5,
            turn_right: false,
            turn_radius_m: 6.0,
            length_after_junction_m: 0.0,
            end_x_m: 195.0,
        };
        match index.min(3) {
            0 => Self {
                street_heading_deg: -12.0,
                road_half_width_m: 5.5,
                parking_width_m: 2.2,
                setback_m: [2.0, 6.0],
                tree_spacing_m: 30.0,
                route: straight,
                ..demo
            },
            1 => Self {
                street_heading_deg: 61.0,
                slope_x: -0.009,
                road_half_width_m: 3.0,
                parking_width_m: 0.0,
                sidewalk_width_m: 2.5,
                cross_street: Some(CrossStreetSpec {
                    at_x_m: 100.0,
                    half_width_m: 3.0,
                    extent_right_m: 60.0,
                    extent_left_m: 60.0,
                }),
                route: RouteSpec {
                    lane_offset_m: 1.2,
                    ..straight
                },
                setback_m: [0.5, 2.0],
                tree_spacing_m: 8.0,
                tree_offset_m: 1.0,
                crown_radius_m: [3.5, 4.8],
                crown_centre_height_m: [6.5, 8.0],
                car_probability: 0.0,
                ..demo
            },
            2 => Self {
                street_heading_deg: 104.0,
                slope_x: 0.005,
                road_half_width_m: 3.5,
                parking_width_m: 0.0,
                markings: false,
                canal: Some(CanalSpec {
                    quay_width_m: 3.0,
                    width_m: 18.0,
                    drop_m: 1.6,
                }),
                cross_street: Some(CrossStreetSpec {
                    at_x_m: 90.0,
                    half_width_m: 3.5,
                    extent_right_m: 0.0,
                    extent_left_m: 60.0,
                }),
                buildings_right: false,
                route: RouteSpec {
                    lane_offset_m: 1.4,
                    ..straight
                },
                tree_spacing_m: 12.0,
                car_probability: 0.0,
                ..demo
            },
            _ => Self {
                street_heading_deg: 197.0,
                slope_x: 0.006,
                road_half_width_m: 4.0,
                parking_width_m: 0.0,
                setback_m: [12.0, 25.0],
                tree_spacing_m: 9.0,
                tree_offset_m: 1.5,
                crown_radius_m: [3.0, 4.2],
                crown_centre_height_m: [6.0, 8.0],
                route: straight,
                car_probability: 0.0,
                ..demo
            },
        }
    }
}
