//! `skytie.gpkg`: one GeoPackage for GIS (QGIS, ArcGIS, GDAL) with the run's results as layers in the
//! campaign CRS ([`layers`] lists them and their attributes; `docs/outputs.md` documents every field).
//! The CRS is taken from `campaign.toml`'s `crs`: `EPSG:<code>` is written as that EPSG system (readers with
//! an EPSG database resolve it); anything else is written as the GeoPackage's "undefined Cartesian" system
//! and reported, so the user can assign the CRS in the GIS.

pub mod layers;
pub mod writer;

pub use layers::{run_layers, RunLayers};
pub use writer::{write_geopackage, FieldType, Geometry, GeometryType, Layer, Srs, Value};

/// The spatial reference system for a campaign `crs` string; `Err` carries the warning for an unknown one
/// (the layers are then written with the undefined Cartesian system).
pub fn srs_for(crs: &str) -> Result<Srs, (Srs, String)> {
    let c = crs.trim();
    let code = c
        .strip_prefix("EPSG:")
        .or_else(|| c.strip_prefix("epsg:"))
        .and_then(|s| s.parse::<i64>().ok())
        .filter(|&v| v > 0);
    match code {
        Some(code) => Ok(Srs::Epsg {
            code,
            definition: None,
        }),
        None => Err((
            Srs::UndefinedCartesian,
            format!(
                "campaign crs '{crs}' is not an EPSG code: the GeoPackage's layers have an undefined CRS; \
                 assign it in your GIS, or set crs = \"EPSG:<code>\" in campaign.toml"
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn epsg_codes_and_unknown_systems() {
        assert_eq!(srs_for("EPSG:28992").unwrap().id(), 28992);
        let (srs, warning) = srs_for("RD New").unwrap_err();
        assert_eq!(srs, Srs::UndefinedCartesian);
        assert!(warning.contains("RD New"));
        assert!(srs_for("").is_err());
    }
}
