//! Known-answer tests of the output writers: PLY layout and size, GeoJSON structure, CSV columns and values.

use skytie_stages::campaign::{
    write_aerial_cameras_csv, write_campaign_toml, write_checkpoints_csv, write_observations_csv,
    write_ply, write_recordings_csv, write_trajectory_geojson, AerialImage, CheckPoint,
    GeoJsonLayer, GeoJsonPoint, Observation, PlyPoint, Recording,
};
use std::collections::BTreeMap;

fn recording(i: usize) -> Recording {
    Recording {
        sigma_xy_m: if i == 0 { Some(0.5) } else { None },
        ..Recording::new(
            &format!("pano_{i:03}"),
            1_560_508_267.25 + i as f64,
            [
                155_000.123_456_789 + i as f64 * 5.0,
                463_000.987_654_321,
                2.0 + 0.25 * i as f64,
            ],
            90.0,
            2.5,
        )
    }
}

#[test]
fn ply_header_is_valid_and_file_size_matches() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("out/tie_points.ply");
    let pts = [
        PlyPoint {
            xyz_world: [155_000.25, 463_000.5, 3.75],
            rgb: [255, 0, 10],
            source: 0,
        },
        PlyPoint {
            xyz_world: [-1.0, 2.0, 1e-9],
            rgb: [1, 2, 3],
            source: -7,
        },
    ];
    write_ply(&p, &pts).unwrap();
    let bytes = std::fs::read(&p).unwrap();
    let end = b"end_header\n";
    let header_len = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).unwrap();
    let lines: Vec<&str> = header.lines().collect();
    assert_eq!(lines[0], "ply");
    assert_eq!(lines[1], "format binary_little_endian 1.0");
    assert!(lines.contains(&"element vertex 2"));
    let props: Vec<&str> = lines
        .iter()
        .copied()
        .filter(|l| l.starts_with("property"))
        .collect();
    assert_eq!(
        props,
        [
            "property double x",
            "property double y",
            "property double z",
            "property uchar red",
            "property uchar green",
            "property uchar blue",
            "property int source"
        ]
    );
    assert_eq!(bytes.len(), header_len + 2 * (3 * 8 + 3 + 4));
    let v1 = &bytes[header_len + 31..];
    assert_eq!(f64::from_le_bytes(v1[0..8].try_into().unwrap()), -1.0);
    assert_eq!(f64::from_le_bytes(v1[16..24].try_into().unwrap()), 1e-9);
    assert_eq!(&v1[24..27], &[1, 2, 3]);
    assert_eq!(i32::from_le_bytes(v1[27..31].try_into().unwrap()), -7);
    let v0 = &bytes[header_len..];
    assert_eq!(f64::from_le_bytes(v0[8..16].try_into().unwrap()), 463_000.5);
}

#[test]
fn geojson_parses_with_expected_features_and_crs() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("trajectory.geojson");
    let mk = |name: &str, n: usize, line: bool| GeoJsonLayer {
        name: name.into(),
        crs: "EPSG:28992".into(),
        points: (0..n)
            .map(|i| {
                let mut properties = BTreeMap::new();
                properties.insert(
                    "image_id".to_string(),
                    serde_json::json!(format!("pano_{i}")),
                );
                GeoJsonPoint {
                    xyz_world: [155_000.0 + i as f64, 463_000.125, 2.0],
                    properties,
                }
            })
            .collect(),
        line,
    };
    write_trajectory_geojson(&p, &[mk("recorded", 3, true), mk("adjusted", 3, false)]).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&p).unwrap()).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    assert_eq!(
        v["crs"]["properties"]["name"],
        "urn:ogc:def:crs:EPSG::28992"
    );
    let features = v["features"].as_array().unwrap();
    assert_eq!(features.len(), 3 + 1 + 3);
    assert_eq!(features[0]["geometry"]["type"], "Point");
    assert_eq!(features[0]["properties"]["layer"], "recorded");
    assert_eq!(features[0]["properties"]["image_id"], "pano_0");
    assert_eq!(
        features[2]["geometry"]["coordinates"][0].as_f64().unwrap(),
        155_002.0
    );
    assert_eq!(features[3]["geometry"]["type"], "LineString");
    assert_eq!(
        features[3]["geometry"]["coordinates"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    assert_eq!(features[6]["properties"]["layer"], "adjusted");
    assert_eq!(
        features[6]["geometry"]["coordinates"][1].as_f64().unwrap(),
        463_000.125
    );

    let mut other = mk("x", 1, false);
    other.crs = "EPSG:4326".into();
    assert!(write_trajectory_geojson(&p, &[mk("a", 1, false), other]).is_err());
}

#[test]
fn recordings_csv_has_documented_columns_and_exact_values() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("mm/recordings.csv");
    let rows: Vec<Recording> = (0..2).map(recording).collect();
    write_recordings_csv(&p, &rows).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "image_id,file,time,x,y,z,heading,camera_height,sigma_xy"
    );
    assert_eq!(lines[1], "pano_000,pano_000.jpg,2019-06-14T10:31:07.250Z,155000.123456789,463000.987654321,2,90,2.5,0.5");
    assert_eq!(lines[2], "pano_001,pano_001.jpg,2019-06-14T10:31:08.250Z,155005.123456789,463000.987654321,2.25,90,2.5,");
    assert_eq!(lines.len(), 3);
}

#[test]
fn other_tables_and_toml_have_documented_columns() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_campaign_toml(
        &d.join("campaign.toml"),
        "Test \"street\"",
        "EPSG:28992",
        Default::default(),
    )
    .unwrap();
    let toml_value: toml::Value =
        toml::from_str(&std::fs::read_to_string(d.join("campaign.toml")).unwrap()).unwrap();
    assert_eq!(toml_value["name"].as_str(), Some("Test \"street\""));
    assert_eq!(toml_value["crs"].as_str(), Some("EPSG:28992"));

    let a = AerialImage {
        file: "n1.png".into(),
        ..AerialImage::ideal("n,1", [1.5, 2.5, 500.0], [0.0; 3], 1000.0, [100, 80])
    };
    write_aerial_cameras_csv(&d.join("nadir.csv"), std::slice::from_ref(&a)).unwrap();
    assert_eq!(
        std::fs::read_to_string(d.join("nadir.csv")).unwrap(),
        "image_id,file,x,y,z,omega,phi,kappa,focal_px,cx,cy,width,height\n\"n,1\",n1.png,1.5,2.5,500,0,0,0,1000,50,40,100,80\n"
    );
    let b = AerialImage {
        k1: -0.1,
        sigma_px: 0.25,
        ..a
    };
    write_aerial_cameras_csv(&d.join("oblique.csv"), &[b]).unwrap();
    let text = std::fs::read_to_string(d.join("oblique.csv")).unwrap();
    assert!(text.starts_with(
        "image_id,file,x,y,z,omega,phi,kappa,focal_px,cx,cy,width,height,k1,k2,p1,p2,sigma_px\n"
    ));
    assert!(text.ends_with(",100,80,-0.1,0,0,0,0.25\n"), "{text}");

    let cp = CheckPoint {
        point_id: "#7".into(),
        x: 1.0,
        y: 2.0,
        z: 3.0,
        sigma_xy_m: None,
        sigma_z_m: Some(0.01),
    };
    write_checkpoints_csv(&d.join("cp.csv"), &[cp]).unwrap();
    assert_eq!(
        std::fs::read_to_string(d.join("cp.csv")).unwrap(),
        "point_id,x,y,z,sigma_z\n\"#7\",1,2,3,0.01\n"
    );
    let ob = Observation {
        point_id: "p".into(),
        image_id: "pano_000".into(),
        u_px: 10.25,
        v_px: 0.5,
    };
    write_observations_csv(&d.join("ob.csv"), &[ob]).unwrap();
    assert_eq!(
        std::fs::read_to_string(d.join("ob.csv")).unwrap(),
        "point_id,image_id,u,v\np,pano_000,10.25,0.5\n"
    );
}
