//! USGS ASCII DEM heightfields.
//!
//! The file is a sequence of 1024-byte blocks (records written with a line break after each
//! block are accepted too): one type-A header record, then one type-B record per profile
//! (a column of posts from south to north), then an optional type-C accuracy record, which is
//! ignored. Fields are read by byte position, as the standard defines them; reals may use
//! FORTRAN `D` exponents.
//!
//! Type A (1-based byte positions): ground units at 529-534 (0 radians, 1 feet, 2 metres,
//! 3 arc-seconds), elevation units at 535-540 (1 feet, 2 metres), spatial resolution x, y, z at
//! 817-852 (three `E12.6`), profile count at 859-864. Type B: row/column ids at 1-12, the
//! number of posts `m` at 13-18, the ground coordinates of the first (southern) post at 25-72,
//! the local datum elevation at 73-96, then `m` elevations as `I6` from byte 145 (146 in the
//! first block, 170 per following block). A post's elevation is `datum + value * z_resolution`
//! in the elevation units; `-32767` marks a void.
//!
//! The mesh (see the heightfield module): metres, x east, y up, z south, origin at the
//! north-west corner of the grid that holds every profile. Posts are placed on the grid by
//! their ground coordinates, so profiles of varying length (the irregular corners of a
//! quadrangle in UTM) leave missing posts, which become borders, never spikes. Ground units in
//! feet are converted; arc-seconds and radians need [`ImportOptions::spacing`], which, when
//! given, also overrides the spacing of metre and foot grids.

use super::error::{ImportError, Source};
use super::heightfield::{heightfield_to_mesh, Heightfield};
use super::options::{ImportOptions, ImportReport, Loader};
use crate::mesh::Mesh;

const BLOCK: usize = 1024;
const FEET: f64 = 0.3048;
/// The void marker of USGS DEMs.
const VOID: i64 = -32767;

pub(crate) fn import_dem(
    source: &Source,
    bytes: &[u8],
    _load: &mut Loader<'_>,
    options: &ImportOptions,
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let dem = parse_dem(source, bytes)?;
    let grid = dem.to_grid(source, options.spacing)?;
    if dem.voids > 0 {
        report.notes.push(format!(
            "{}: {} posts are voids (-32767)",
            source.name, dem.voids
        ));
    }
    heightfield_to_mesh(source, &grid, "terrain", report)
}

/// One profile: a column of posts from south to north.
#[derive(Debug)]
struct Profile {
    /// Ground coordinates of the first (southern) post, in ground units.
    x: f64,
    y: f64,
    /// Elevations in metres, south to north; NaN for voids.
    elevations: Vec<f32>,
}

#[derive(Debug)]
struct Dem {
    /// 0 radians, 1 feet, 2 metres, 3 arc-seconds.
    ground_units: i64,
    /// Spacing between posts along x and y, in ground units.
    resolution: [f64; 2],
    profiles: Vec<Profile>,
    voids: usize,
}

/// A fixed-width field, 1-based inclusive byte positions as the standard lists them.
fn field(record: &[u8], first: usize, last: usize) -> &str {
    let bytes = record.get(first - 1..last).unwrap_or(&[]);
    std::str::from_utf8(bytes).unwrap_or("").trim()
}

fn parse_real(text: &str) -> Option<f64> {
    let text = text.replace(['D', 'd'], "E");
    text.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// The type A record (units, resolution, profile count), then each profile's records in turn.
fn parse_dem(source: &Source, bytes: &[u8]) -> Result<Dem, ImportError> {
    let data = blocks(source, bytes)?;
    let header = HeaderA::parse(source, &data)?;
    let mut profiles = Vec::with_capacity(header.columns);
    let mut voids = 0;
    let mut block = 1;
    for p in 0..header.columns {
        let (profile, blocks_needed) = read_profile(source, &data, &header, p, block, &mut voids)?;
        profiles.push(profile);
        block += blocks_needed;
    }
    Ok(Dem {
        ground_units: header.ground_units,
        resolution: [header.res_x, header.res_y],
        profiles,
        voids,
    })
}

/// What the type A record says that reading the profiles needs.
struct HeaderA {
    ground_units: i64,
    /// Metres per elevation unit.
    elevation_scale: f64,
    res_x: f64,
    res_y: f64,
    /// Elevation units per raw post value.
    res_z: f64,
    /// Profiles, at least one and no more than the records after the header.
    columns: usize,
}

impl HeaderA {
    fn parse(source: &Source, data: &[u8]) -> Result<Self, ImportError> {
        let a = &data[..BLOCK];
        let real = |first, last, name: &str| {
            parse_real(field(a, first, last)).ok_or_else(|| {
                source.malformed(
                    format!("type A record, bytes {first}-{last} ({name})"),
                    format!("expected a number, found '{}'", field(a, first, last)),
                )
            })
        };
        let int = |first, last, name: &str| {
            field(a, first, last).parse::<i64>().map_err(|_| {
                source.malformed(
                    format!("type A record, bytes {first}-{last} ({name})"),
                    format!("expected an integer, found '{}'", field(a, first, last)),
                )
            })
        };
        let ground_units = int(529, 534, "ground units")?;
        let elevation_units = int(535, 540, "elevation units")?;
        let res_x = real(817, 828, "x resolution")?;
        let res_y = real(829, 840, "y resolution")?;
        let res_z = real(841, 852, "z resolution")?;
        let columns = int(859, 864, "number of profiles")?;
        if !(0..=3).contains(&ground_units) {
            return Err(source.malformed(
                "type A record, bytes 529-534 (ground units)",
                format!("unknown code {ground_units} (0 to 3)"),
            ));
        }
        let elevation_scale = match elevation_units {
            1 => FEET,
            2 => 1.0,
            other => {
                return Err(source.malformed(
                    "type A record, bytes 535-540 (elevation units)",
                    format!("unknown code {other} (1 feet, 2 metres)"),
                ))
            }
        };
        if !(res_x > 0.0 && res_y > 0.0 && res_z > 0.0) {
            return Err(source.malformed(
                "type A record, bytes 817-852 (resolution)",
                format!("x, y and z resolution must be positive, not {res_x}, {res_y}, {res_z}"),
            ));
        }
        let available_blocks = data.len() / BLOCK - 1;
        let columns = usize::try_from(columns)
            .ok()
            .filter(|&c| c >= 1 && c <= available_blocks)
            .ok_or_else(|| {
                source.malformed(
                    "type A record, bytes 859-864 (number of profiles)",
                    format!("{columns} profiles, but the file has {available_blocks} records after the header"),
                )
            })?;
        Ok(HeaderA {
            ground_units,
            elevation_scale,
            res_x,
            res_y,
            res_z,
            columns,
        })
    }
}

/// Profile `p` (0-based), whose type B record starts at `block`: its posts (voids counted)
/// and how many records it takes.
fn read_profile(
    source: &Source,
    data: &[u8],
    header: &HeaderA,
    p: usize,
    block: usize,
    voids: &mut usize,
) -> Result<(Profile, usize), ImportError> {
    let at = || format!("profile {} (record at byte {})", p + 1, block * BLOCK);
    let first = data
        .get(block * BLOCK..(block + 1) * BLOCK)
        .ok_or_else(|| source.truncated(format!("{} is missing", at())))?;
    let b_int = |f, l, name: &str| {
        field(first, f, l).parse::<i64>().map_err(|_| {
            source.malformed(
                at(),
                format!(
                    "bytes {f}-{l} ({name}): expected an integer, found '{}'",
                    field(first, f, l)
                ),
            )
        })
    };
    let b_real = |f, l, name: &str| {
        parse_real(field(first, f, l)).ok_or_else(|| {
            source.malformed(
                at(),
                format!(
                    "bytes {f}-{l} ({name}): expected a number, found '{}'",
                    field(first, f, l)
                ),
            )
        })
    };
    let m = b_int(13, 18, "number of posts")?;
    let n = b_int(19, 24, "number of columns")?;
    if n != 1 {
        return Err(source.malformed(at(), format!("{n} columns in a profile (1 expected)")));
    }
    let x = b_real(25, 48, "x")?;
    let y = b_real(49, 72, "y")?;
    let datum = b_real(73, 96, "datum elevation")?;
    let m = usize::try_from(m).map_err(|_| source.malformed(at(), format!("{m} posts")))?;
    let blocks_needed = if m <= 146 {
        1
    } else {
        1 + (m - 146).div_ceil(170)
    };
    if block + blocks_needed > data.len() / BLOCK {
        return Err(source.truncated(format!(
            "{} has {m} posts in {blocks_needed} records; the file ends before",
            at()
        )));
    }
    let posts = Posts {
        data,
        block,
        count: m,
        datum,
    };
    let elevations = posts.read(source, header, &at, voids)?;
    Ok((Profile { x, y, elevations }, blocks_needed))
}

/// A profile's posts: 146 in its first record (from byte 145), 170 in each following one.
struct Posts<'a> {
    data: &'a [u8],
    block: usize,
    count: usize,
    /// Elevation of the datum the posts are relative to, in elevation units.
    datum: f64,
}

impl Posts<'_> {
    /// Elevations in metres, NaN for voids (counted in `voids`).
    fn read(
        &self,
        source: &Source,
        header: &HeaderA,
        at: &dyn Fn() -> String,
        voids: &mut usize,
    ) -> Result<Vec<f32>, ImportError> {
        let (data, block) = (self.data, self.block);
        let mut elevations = Vec::with_capacity(self.count);
        for k in 0..self.count {
            let (b, slot) = if k < 146 {
                (block, 144 + 6 * k)
            } else {
                (block + 1 + (k - 146) / 170, 6 * ((k - 146) % 170))
            };
            let start = b * BLOCK + slot;
            let text = std::str::from_utf8(&data[start..start + 6])
                .unwrap_or("")
                .trim();
            let raw: i64 = text.parse().map_err(|_| {
                source.malformed(
                    at(),
                    format!(
                        "post {}: expected an integer elevation, found '{text}'",
                        k + 1
                    ),
                )
            })?;
            if raw <= VOID {
                *voids += 1;
                elevations.push(f32::NAN);
            } else {
                let metres = (self.datum + raw as f64 * header.res_z) * header.elevation_scale;
                elevations.push(metres as f32);
            }
        }
        Ok(elevations)
    }
}

/// The records as contiguous 1024-byte blocks: the file itself, or the file without the line
/// breaks some writers put after every record.
fn blocks<'a>(source: &Source, bytes: &'a [u8]) -> Result<std::borrow::Cow<'a, [u8]>, ImportError> {
    let data: std::borrow::Cow<'a, [u8]> = if bytes.len() % BLOCK == 0 {
        bytes.into()
    } else {
        let stripped: Vec<u8> = bytes
            .iter()
            .copied()
            .filter(|&b| b != b'\n' && b != b'\r')
            .collect();
        if stripped.len() % BLOCK != 0 {
            return Err(source.truncated(format!(
                "{} bytes is not a whole number of 1024-byte records",
                bytes.len()
            )));
        }
        stripped.into()
    };
    if data.len() < 2 * BLOCK {
        return Err(source.truncated(format!(
            "{} bytes: a DEM needs a 1024-byte header and at least one profile record",
            data.len()
        )));
    }
    if !data[..BLOCK].is_ascii() {
        return Err(source.malformed("type A record", "not ASCII text: not a USGS ASCII DEM"));
    }
    Ok(data)
}

impl Dem {
    /// Places the profiles on a regular grid (row 0 north).
    fn to_grid(&self, source: &Source, spacing: Option<f32>) -> Result<Heightfield, ImportError> {
        let spacing = match (spacing, self.ground_units) {
            (Some(s), _) => [s, s],
            (None, 1) => self.resolution.map(|r| (r * FEET) as f32),
            (None, 2) => self.resolution.map(|r| r as f32),
            (None, units) => {
                return Err(ImportError::MissingOption {
                    file: source.name.clone(),
                    message: format!(
                        "ground coordinates are in {}: give the spacing in metres per post \
                         (`--spacing M`)",
                        if units == 0 { "radians" } else { "arc-seconds" }
                    ),
                })
            }
        };
        let [res_x, res_y] = self.resolution;
        let min_x = self
            .profiles
            .iter()
            .map(|p| p.x)
            .fold(f64::INFINITY, f64::min);
        let min_y = self
            .profiles
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        let posts: usize = self.profiles.iter().map(|p| p.elevations.len()).sum();
        // A malformed coordinate must not become a huge allocation.
        let limit = posts.saturating_mul(16).max(1 << 20) as f64;
        let mut placed = Vec::with_capacity(self.profiles.len());
        let (mut width, mut depth) = (0usize, 0usize);
        for (i, p) in self.profiles.iter().enumerate() {
            let at = || format!("profile {}", i + 1);
            let col = (p.x - min_x) / res_x;
            let row = (p.y - min_y) / res_y;
            if (col - col.round()).abs() > 0.25 || (row - row.round()).abs() > 0.25 {
                return Err(source.unsupported(
                    at(),
                    format!(
                        "first post at ({}, {}) is not on the grid of the other profiles \
                         (spacing {res_x} x {res_y})",
                        p.x, p.y
                    ),
                ));
            }
            if col.round() >= limit || row.round() + p.elevations.len() as f64 >= limit {
                return Err(source.malformed(
                    at(),
                    format!(
                        "first post at ({}, {}) is far outside the other profiles",
                        p.x, p.y
                    ),
                ));
            }
            let (col, row) = (col.round() as usize, row.round() as usize);
            width = width.max(col + 1);
            depth = depth.max(row + p.elevations.len());
            placed.push((col, row));
        }
        let cells = width
            .checked_mul(depth)
            .filter(|&c| c as f64 <= limit)
            .ok_or_else(|| {
                source.malformed(
                    "profiles",
                    format!("{posts} posts spread over a {width} x {depth} grid"),
                )
            })?;
        let mut heights = vec![f32::NAN; cells];
        let mut filled = vec![false; cells];
        for (i, (p, &(col, row))) in self.profiles.iter().zip(&placed).enumerate() {
            for (k, &h) in p.elevations.iter().enumerate() {
                // Row 0 of the heightfield is the northern edge.
                let grid_row = depth - 1 - (row + k);
                let cell = grid_row * width + col;
                if filled[cell] {
                    return Err(source.malformed(
                        format!("profile {}", i + 1),
                        format!("post {} lands on a post of another profile", k + 1),
                    ));
                }
                filled[cell] = true;
                heights[cell] = h;
            }
        }
        Ok(Heightfield {
            width,
            depth,
            spacing,
            heights,
        })
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A small DEM in metres: `profiles` are (x, y, elevations), resolution 30 x 30 x 1.
    pub(crate) fn dem_bytes(profiles: &[(f64, f64, Vec<i64>)]) -> Vec<u8> {
        let mut a = vec![b' '; BLOCK];
        let put = |rec: &mut Vec<u8>, first: usize, text: &str| {
            let last = first - 1 + text.len();
            rec[first - 1..last].copy_from_slice(text.as_bytes());
        };
        put(&mut a, 1, "TEST DEM");
        put(&mut a, 529, &format!("{:>6}{:>6}{:>6}", 2, 2, 4));
        put(&mut a, 817, "0.300000E+020.300000E+020.100000E+01");
        put(&mut a, 853, &format!("{:>6}{:>6}", 1, profiles.len()));
        let mut out = a;
        for (j, (x, y, elevations)) in profiles.iter().enumerate() {
            let mut text = format!(
                "{:>6}{:>6}{:>6}{:>6}{:>24}{:>24}{:>24}{:>24}{:>24}",
                1,
                j + 1,
                elevations.len(),
                1,
                fortran(*x),
                fortran(*y),
                fortran(0.0),
                fortran(0.0),
                fortran(0.0)
            );
            let mut in_block = 144;
            let mut capacity = 146;
            for e in elevations {
                if capacity == 0 {
                    text.push_str(&" ".repeat(BLOCK - in_block));
                    in_block = 0;
                    capacity = 170;
                }
                text.push_str(&format!("{e:>6}"));
                in_block += 6;
                capacity -= 1;
            }
            text.push_str(&" ".repeat(BLOCK - in_block));
            assert_eq!(text.len() % BLOCK, 0);
            out.extend_from_slice(text.as_bytes());
        }
        out
    }

    /// A real with a FORTRAN `D` exponent (`5.000000000000000D3`).
    fn fortran(v: f64) -> String {
        format!("{v:.15E}").replace('E', "D")
    }

    fn src() -> Source {
        Source {
            name: "t.dem".to_owned(),
        }
    }

    #[test]
    fn reads_fortran_reals() {
        assert_eq!(parse_real("0.557945011821133D+06"), Some(557945.011821133));
        assert_eq!(parse_real("0.300000E+02"), Some(30.0));
        assert_eq!(parse_real("NaN"), None);
        assert_eq!(parse_real(""), None);
    }

    #[test]
    fn irregular_profiles_leave_holes_not_spikes() {
        // Three profiles; the middle starts one post further north and is longer (spans 200
        // posts, so it continues in a second record), the last is short.
        let long: Vec<i64> = (0..200).map(|k| 100 + k).collect();
        let bytes = dem_bytes(&[
            (1000.0, 5000.0, vec![10, 11, 12]),
            (1030.0, 5030.0, long.clone()),
            (1060.0, 5000.0, vec![30, VOID, 32]),
        ]);
        let dem = parse_dem(&src(), &bytes).unwrap();
        assert_eq!(dem.profiles.len(), 3);
        assert_eq!(dem.profiles[1].elevations.len(), 200);
        assert_eq!(dem.profiles[1].elevations[199], 299.0);
        assert_eq!(dem.voids, 1);
        let grid = dem.to_grid(&src(), None).unwrap();
        assert_eq!((grid.width, grid.depth), (3, 201));
        let at =
            |col: usize, south_row: usize| grid.heights[(grid.depth - 1 - south_row) * 3 + col];
        assert_eq!(at(0, 0), 10.0);
        assert_eq!(at(1, 1), 100.0);
        assert!(at(1, 0).is_nan());
        assert!(at(2, 1).is_nan());
        assert_eq!(at(2, 2), 32.0);
        let mut report = ImportReport::default();
        let mesh = heightfield_to_mesh(&src(), &grid, "terrain", &mut report).unwrap();
        mesh.validate().unwrap();
        // Only the cell between columns 0 and 1, rows 1..2 north is complete.
        assert_eq!(mesh.triangles.len(), 2);
        let ys: Vec<f32> = mesh.positions.iter().map(|p| p[1]).collect();
        assert!(ys.iter().all(|&y| (10.0..=299.0).contains(&y)), "{ys:?}");
    }

    #[test]
    fn rejects_bad_records() {
        let good = dem_bytes(&[(0.0, 0.0, vec![1, 2]), (30.0, 0.0, vec![3, 4])]);
        assert!(parse_dem(&src(), &good).is_ok());
        let err = |bytes: &[u8]| parse_dem(&src(), bytes).err().unwrap().to_string();
        assert!(
            err(&good[..1500]).contains("truncated"),
            "{}",
            err(&good[..1500])
        );
        assert!(err(&good[..BLOCK * 2]).contains("number of profiles"));
        let mut bad = good.clone();
        bad[BLOCK + 144..BLOCK + 150].copy_from_slice(b"  1x 3");
        assert!(
            err(&bad).contains("profile 1") && err(&bad).contains("post 1"),
            "{}",
            err(&bad)
        );
        let mut bad = good.clone();
        bad[816..828].copy_from_slice(b"    garbage ");
        assert!(err(&bad).contains("x resolution"), "{}", err(&bad));
        let mut bad = good.clone();
        bad[BLOCK + 12..BLOCK + 18].copy_from_slice(b"   999");
        assert!(err(&bad).contains("truncated"), "{}", err(&bad));
        // With a line break after each record it reads the same.
        let mut lines = Vec::new();
        for chunk in good.chunks(BLOCK) {
            lines.extend_from_slice(chunk);
            lines.extend_from_slice(b"\r\n");
        }
        assert_eq!(parse_dem(&src(), &lines).unwrap().profiles.len(), 2);
    }

    #[test]
    fn arc_seconds_need_a_spacing() {
        let mut bytes = dem_bytes(&[(0.0, 0.0, vec![1, 2]), (30.0, 0.0, vec![3, 4])]);
        bytes[528..534].copy_from_slice(b"     3");
        let dem = parse_dem(&src(), &bytes).unwrap();
        let err = dem.to_grid(&src(), None).err().unwrap().to_string();
        assert!(err.contains("arc-seconds"), "{err}");
        let grid = dem.to_grid(&src(), Some(25.0)).unwrap();
        assert_eq!(grid.spacing, [25.0, 25.0]);
    }
}
