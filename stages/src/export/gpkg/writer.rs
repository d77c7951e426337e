//! A minimal GeoPackage writer (OGC GeoPackage Encoding Standard 1.4: an SQLite database with the
//! `gpkg_spatial_ref_sys`, `gpkg_contents` and `gpkg_geometry_columns` tables and one feature table per
//! layer, geometries as StandardGeoPackageBinary = "GP" header + ISO WKB). Only what skytie's layers need:
//! POINT Z and LINESTRING Z features with TEXT / REAL / INTEGER attributes, one spatial reference system per
//! file, no spatial index. SQLite comes bundled with `rusqlite`, so no system library is needed.
//!
//! Deterministic: the caller gives `last_change`; the same layers give the same bytes. Written to a
//! temporary file next to the target and renamed when complete.

use rusqlite::{params_from_iter, Connection};
use std::path::{Path, PathBuf};

/// `PRAGMA application_id` of a GeoPackage ("GPKG").
pub const GPKG_APPLICATION_ID: i32 = 0x4750_4B47;
/// `PRAGMA user_version` of GeoPackage 1.4.0.
pub const GPKG_USER_VERSION: i32 = 10400;

/// The spatial reference system of all layers of a file.
#[derive(Clone, Debug, PartialEq)]
pub enum Srs {
    /// An EPSG code; `definition` is its WKT when known, else `undefined` (readers look the code up).
    Epsg {
        code: i64,
        definition: Option<String>,
    },
    /// The spec's "undefined Cartesian SRS" (srs_id −1).
    UndefinedCartesian,
}

impl Srs {
    /// The srs_id the layers use.
    pub fn id(&self) -> i64 {
        match self {
            Srs::Epsg { code, .. } => *code,
            Srs::UndefinedCartesian => -1,
        }
    }
}

/// Geometry of a feature, world coordinates (x east, y north, z up), metres.
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    PointZ([f64; 3]),
    LineStringZ(Vec<[f64; 3]>),
}

impl Geometry {
    fn points(&self) -> &[[f64; 3]] {
        match self {
            Geometry::PointZ(p) => std::slice::from_ref(p),
            Geometry::LineStringZ(v) => v,
        }
    }

    /// StandardGeoPackageBinary: magic "GP", version 0, flags (little endian, no envelope), srs_id, ISO WKB.
    pub fn to_gpkg_blob(&self, srs_id: i64) -> Vec<u8> {
        let pts = self.points();
        let mut b = Vec::with_capacity(8 + 9 + 24 * pts.len());
        b.extend_from_slice(b"GP");
        b.push(0);
        b.push(0b0000_0001);
        b.extend_from_slice(&(srs_id as i32).to_le_bytes());
        b.push(1); // WKB little endian
        match self {
            Geometry::PointZ(p) => {
                b.extend_from_slice(&1001u32.to_le_bytes());
                p.iter().for_each(|v| b.extend_from_slice(&v.to_le_bytes()));
            }
            Geometry::LineStringZ(v) => {
                b.extend_from_slice(&1002u32.to_le_bytes());
                b.extend_from_slice(&(v.len() as u32).to_le_bytes());
                for p in v {
                    p.iter().for_each(|c| b.extend_from_slice(&c.to_le_bytes()));
                }
            }
        }
        b
    }
}

/// An attribute value (`None` = NULL).
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Text(String),
    Real(Option<f64>),
    Int(Option<i64>),
}

impl rusqlite::ToSql for Value {
    fn to_sql(&self) -> rusqlite::Result<rusqlite::types::ToSqlOutput<'_>> {
        use rusqlite::types::{ToSqlOutput, Value as V};
        Ok(ToSqlOutput::Owned(match self {
            Value::Text(s) => V::Text(s.clone()),
            Value::Real(Some(v)) if v.is_finite() => V::Real(*v),
            Value::Int(Some(v)) => V::Integer(*v),
            _ => V::Null,
        }))
    }
}

/// Column type of an attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldType {
    Text,
    Real,
    Integer,
}

/// The geometry type of a layer's features (all with Z).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GeometryType {
    Point,
    LineString,
}

impl GeometryType {
    fn name(self) -> &'static str {
        match self {
            GeometryType::Point => "POINT",
            GeometryType::LineString => "LINESTRING",
        }
    }

    fn admits(self, g: &Geometry) -> bool {
        matches!(
            (self, g),
            (GeometryType::Point, Geometry::PointZ(_))
                | (GeometryType::LineString, Geometry::LineStringZ(_))
        )
    }
}

/// One feature layer.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    /// Table name (letters, digits, `_`).
    pub name: String,
    pub geometry: GeometryType,
    pub description: String,
    pub fields: Vec<(String, FieldType)>,
    /// (geometry, one value per field).
    pub features: Vec<(Geometry, Vec<Value>)>,
}

fn sql_err(path: &Path, e: impl std::fmt::Display) -> std::io::Error {
    std::io::Error::other(format!("{}: GeoPackage: {e}", path.display()))
}

fn valid_name(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
}

const CORE_TABLES: &str = "
CREATE TABLE gpkg_spatial_ref_sys (srs_name TEXT NOT NULL, srs_id INTEGER PRIMARY KEY, organization TEXT NOT NULL,
  organization_coordsys_id INTEGER NOT NULL, definition TEXT NOT NULL, description TEXT);
CREATE TABLE gpkg_contents (table_name TEXT NOT NULL PRIMARY KEY, data_type TEXT NOT NULL, identifier TEXT UNIQUE,
  description TEXT DEFAULT '', last_change DATETIME NOT NULL, min_x DOUBLE, min_y DOUBLE, max_x DOUBLE,
  max_y DOUBLE, srs_id INTEGER, CONSTRAINT fk_gc_r_srs_id FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys(srs_id));
CREATE TABLE gpkg_geometry_columns (table_name TEXT NOT NULL, column_name TEXT NOT NULL,
  geometry_type_name TEXT NOT NULL, srs_id INTEGER NOT NULL, z TINYINT NOT NULL, m TINYINT NOT NULL,
  CONSTRAINT pk_geom_cols PRIMARY KEY (table_name, column_name), CONSTRAINT uk_gc_table_name UNIQUE (table_name),
  CONSTRAINT fk_gc_tn FOREIGN KEY (table_name) REFERENCES gpkg_contents(table_name),
  CONSTRAINT fk_gc_srs FOREIGN KEY (srs_id) REFERENCES gpkg_spatial_ref_sys (srs_id));
INSERT INTO gpkg_spatial_ref_sys VALUES ('Undefined cartesian SRS', -1, 'NONE', -1, 'undefined',
  'undefined cartesian coordinate reference system');
INSERT INTO gpkg_spatial_ref_sys VALUES ('Undefined geographic SRS', 0, 'NONE', 0, 'undefined',
  'undefined geographic coordinate reference system');
INSERT INTO gpkg_spatial_ref_sys VALUES ('WGS 84 geodetic', 4326, 'EPSG', 4326, 'GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",
SPHEROID[\"WGS 84\",6378137,298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0,
AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],AUTHORITY[\"EPSG\",\"4326\"]]',
  'longitude/latitude coordinates in decimal degrees on the WGS 84 spheroid');
";

/// Writes `layers` into a new GeoPackage at `path` (replacing it atomically). `last_change` is the
/// `gpkg_contents.last_change` timestamp (ISO 8601 UTC, e.g. `2020-01-01T00:00:00.000Z`).
pub fn write_geopackage(
    path: &Path,
    srs: &Srs,
    layers: &[Layer],
    last_change: &str,
) -> std::io::Result<()> {
    for l in layers {
        let bad = std::iter::once(&l.name)
            .chain(l.fields.iter().map(|(n, _)| n))
            .find(|n| !valid_name(n) || n.as_str() == "fid" || n.as_str() == "geom");
        if let Some(n) = bad {
            return Err(sql_err(path, format!("invalid table or column name '{n}'")));
        }
    }
    let tmp = PathBuf::from(format!("{}.tmp-{}", path.display(), std::process::id()));
    let _ = std::fs::remove_file(&tmp);
    let result = fill(&tmp, srs, layers, last_change);
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(sql_err(path, e));
    }
    std::fs::rename(&tmp, path)
}

fn fill(tmp: &Path, srs: &Srs, layers: &[Layer], last_change: &str) -> rusqlite::Result<()> {
    let mut db = Connection::open(tmp)?;
    db.pragma_update(None, "application_id", GPKG_APPLICATION_ID)?;
    db.pragma_update(None, "user_version", GPKG_USER_VERSION)?;
    db.pragma_update(None, "journal_mode", "OFF")?;
    let tx = db.transaction()?;
    tx.execute_batch(CORE_TABLES)?;
    if let Srs::Epsg { code, definition } = srs {
        if *code != 4326 {
            tx.execute(
                "INSERT INTO gpkg_spatial_ref_sys VALUES (?1, ?2, 'EPSG', ?2, ?3, ?4)",
                rusqlite::params![
                    format!("EPSG:{code}"),
                    code,
                    definition.as_deref().unwrap_or("undefined"),
                    "the campaign's crs (campaign.toml)"
                ],
            )?;
        }
    }
    for l in layers {
        add_layer(&tx, srs.id(), l, last_change)?;
    }
    tx.commit()?;
    db.execute_batch("VACUUM")?;
    Ok(())
}

fn add_layer(
    tx: &rusqlite::Transaction<'_>,
    srs_id: i64,
    l: &Layer,
    last_change: &str,
) -> rusqlite::Result<()> {
    let geometry_type = l.geometry.name();
    let columns: Vec<String> = l
        .fields
        .iter()
        .map(|(n, t)| {
            let ty = match t {
                FieldType::Text => "TEXT",
                FieldType::Real => "REAL",
                FieldType::Integer => "INTEGER",
            };
            format!(", \"{n}\" {ty}")
        })
        .collect();
    tx.execute_batch(&format!(
        "CREATE TABLE \"{}\" (fid INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, geom {geometry_type}{});",
        l.name,
        columns.concat()
    ))?;
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let names: Vec<String> = l.fields.iter().map(|(n, _)| format!(", \"{n}\"")).collect();
    let marks: Vec<String> = (0..l.fields.len())
        .map(|i| format!(", ?{}", i + 2))
        .collect();
    let mut insert = tx.prepare(&format!(
        "INSERT INTO \"{}\" (geom{}) VALUES (?1{})",
        l.name,
        names.concat(),
        marks.concat()
    ))?;
    for (g, values) in &l.features {
        if !l.geometry.admits(g) || values.len() != l.fields.len() {
            return Err(rusqlite::Error::InvalidParameterName(format!(
                "layer {}: a feature does not match the layer's geometry type or fields",
                l.name
            )));
        }
        for p in g.points() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let geom = rusqlite::types::Value::Blob(g.to_gpkg_blob(srs_id));
        let params = std::iter::once(&geom as &dyn rusqlite::ToSql)
            .chain(values.iter().map(|v| v as &dyn rusqlite::ToSql));
        insert.execute(params_from_iter(params))?;
    }
    let bound = |v: f64| v.is_finite().then_some(v);
    tx.execute(
        "INSERT INTO gpkg_contents VALUES (?1, 'features', ?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)",
        rusqlite::params![
            l.name,
            l.description,
            last_change,
            bound(lo[0]),
            bound(lo[1]),
            bound(hi[0]),
            bound(hi[1]),
            srs_id
        ],
    )?;
    tx.execute(
        "INSERT INTO gpkg_geometry_columns VALUES (?1, 'geom', ?2, ?3, 1, 0)",
        rusqlite::params![l.name, geometry_type, srs_id],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn point_blob_is_gp_header_plus_iso_wkb() {
        let b = Geometry::PointZ([1.0, 2.0, 3.0]).to_gpkg_blob(28992);
        assert_eq!(&b[..4], b"GP\x00\x01");
        assert_eq!(i32::from_le_bytes(b[4..8].try_into().unwrap()), 28992);
        assert_eq!(b[8], 1);
        assert_eq!(u32::from_le_bytes(b[9..13].try_into().unwrap()), 1001);
        assert_eq!(f64::from_le_bytes(b[29..37].try_into().unwrap()), 3.0);
        assert_eq!(b.len(), 37);
        let l = Geometry::LineStringZ(vec![[0.0; 3], [1.0; 3]]).to_gpkg_blob(-1);
        assert_eq!(u32::from_le_bytes(l[9..13].try_into().unwrap()), 1002);
        assert_eq!(l.len(), 8 + 9 + 48);
    }

    #[test]
    fn writes_layers_that_read_back_with_sqlite() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("t.gpkg");
        let layer = Layer {
            name: "pts".into(),
            geometry: GeometryType::Point,
            description: "test".into(),
            fields: vec![
                ("name".into(), FieldType::Text),
                ("v".into(), FieldType::Real),
            ],
            features: vec![
                (
                    Geometry::PointZ([10.0, 20.0, 1.0]),
                    vec![Value::Text("a".into()), Value::Real(Some(1.5))],
                ),
                (
                    Geometry::PointZ([11.0, 19.0, 1.0]),
                    vec![Value::Text("b".into()), Value::Real(None)],
                ),
            ],
        };
        let srs = Srs::Epsg {
            code: 28992,
            definition: None,
        };
        write_geopackage(
            &p,
            &srs,
            std::slice::from_ref(&layer),
            "2020-01-01T00:00:00.000Z",
        )
        .unwrap();
        let first = std::fs::read(&p).unwrap();
        write_geopackage(&p, &srs, &[layer], "2020-01-01T00:00:00.000Z").unwrap();
        assert_eq!(first, std::fs::read(&p).unwrap(), "deterministic bytes");
        let db = Connection::open(&p).unwrap();
        let app: i32 = db
            .query_row("PRAGMA application_id", [], |r| r.get(0))
            .unwrap();
        assert_eq!(app, GPKG_APPLICATION_ID);
        let (n, minx, maxy): (i64, f64, f64) = db
            .query_row(
                "SELECT (SELECT count(*) FROM pts), min_x, max_y FROM gpkg_contents WHERE table_name='pts'",
                [],
                |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)),
            )
            .unwrap();
        assert_eq!((n, minx, maxy), (2, 10.0, 20.0));
        let null: Option<f64> = db
            .query_row("SELECT v FROM pts WHERE name='b'", [], |r| r.get(0))
            .unwrap();
        assert_eq!(null, None);
        assert!(!d.path().read_dir().unwrap().any(|e| e
            .unwrap()
            .file_name()
            .to_string_lossy()
            .contains(".tmp-")));
    }

    #[test]
    fn rejects_names_that_are_not_plain_identifiers() {
        let d = tempfile::tempdir().unwrap();
        let layer = Layer {
            name: "bad name".into(),
            geometry: GeometryType::Point,
            description: String::new(),
            fields: vec![],
            features: vec![],
        };
        let e = write_geopackage(
            &d.path().join("t.gpkg"),
            &Srs::UndefinedCartesian,
            &[layer],
            "x",
        )
        .unwrap_err();
        assert!(e.to_string().contains("bad name"), "{e}");
    }
}
