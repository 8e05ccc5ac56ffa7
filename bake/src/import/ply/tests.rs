use super::properties::byte_colour;
use super::*;
use crate::base::colour::srgb_to_linear;

fn src() -> Source {
    Source {
        name: "t.ply".to_owned(),
    }
}

#[derive(Clone, Copy)]
enum Format {
    Ascii,
    Le,
    Be,
}

/// Position, normal, RGBA bytes, UV.
type SampleVertex = ([f32; 3], [f32; 3], [u8; 4], [f32; 2]);

/// A quad and a triangle over five vertices with normals, byte colours and UVs.
fn sample(format: Format) -> Vec<u8> {
    let verts: [SampleVertex; 5] = [
        (
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [255, 0, 0, 255],
            [0.0, 0.0],
        ),
        (
            [1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [0, 255, 0, 128],
            [1.0, 0.0],
        ),
        (
            [1.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0, 0, 255, 255],
            [1.0, 1.0],
        ),
        (
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [10, 20, 30, 255],
            [0.0, 1.0],
        ),
        (
            [0.5, 2.0, 0.25],
            [0.0, 0.6, 0.8],
            [200, 100, 50, 0],
            [0.5, 1.5],
        ),
    ];
    let faces: [&[i32]; 2] = [&[0, 1, 2, 3], &[3, 2, 4]];
    let name = match format {
        Format::Ascii => "ascii",
        Format::Le => "binary_little_endian",
        Format::Be => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {name} 1.0\ncomment TextureFile skin.png\nelement vertex 5\n\
         property float x\nproperty float y\nproperty float z\nproperty float nx\n\
         property float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nproperty uchar alpha\nproperty float u\nproperty float v\n\
         element face 2\nproperty list uchar int vertex_indices\nproperty uchar flags\n\
         end_header\n"
    )
    .into_bytes();
    let f = |out: &mut Vec<u8>, v: f32| match format {
        Format::Le => out.extend_from_slice(&v.to_le_bytes()),
        Format::Be => out.extend_from_slice(&v.to_be_bytes()),
        Format::Ascii => out.extend_from_slice(format!("{v} ").as_bytes()),
    };
    for (p, n, c, uv) in verts {
        for v in p.into_iter().chain(n) {
            f(&mut out, v);
        }
        for b in c {
            match format {
                Format::Ascii => out.extend_from_slice(format!("{b} ").as_bytes()),
                _ => out.push(b),
            }
        }
        for v in uv {
            f(&mut out, v);
        }
        if let Format::Ascii = format {
            out.push(b'\n');
        }
    }
    for face in faces {
        match format {
            Format::Ascii => {
                let list: Vec<String> = face.iter().map(|i| i.to_string()).collect();
                out.extend_from_slice(format!("{} {} 7\n", face.len(), list.join(" ")).as_bytes());
            }
            Format::Le | Format::Be => {
                out.push(face.len() as u8);
                for &i in face {
                    match format {
                        Format::Le => out.extend_from_slice(&i.to_le_bytes()),
                        _ => out.extend_from_slice(&i.to_be_bytes()),
                    }
                }
                out.push(7);
            }
        }
    }
    out
}

fn parse(bytes: &[u8]) -> Result<Mesh, ImportError> {
    parse_ply(&src(), bytes, &mut ImportReport::default())
}

#[test]
fn ascii_and_both_binaries_give_the_same_mesh() {
    let ascii = parse(&sample(Format::Ascii)).unwrap();
    let le = parse(&sample(Format::Le)).unwrap();
    let be = parse(&sample(Format::Be)).unwrap();
    assert_eq!(ascii, le);
    assert_eq!(ascii, be);
    ascii.validate().unwrap();
    assert_eq!(ascii.positions.len(), 5);
    assert_eq!(ascii.normals.len(), 5);
    assert_eq!(ascii.uvs.len(), 5);
    assert_eq!(ascii.colors.len(), 5);
    // The quad becomes a fan of two triangles, then the triangle.
    let tris: Vec<[u32; 3]> = ascii.triangles.iter().map(|t| t.position).collect();
    assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3], [3, 2, 4]]);
    assert!(ascii
        .triangles
        .iter()
        .all(|t| t.uv == t.position && t.normal == t.position));
    assert_eq!(ascii.uvs[4], [0.5, -0.5]);
    assert_eq!(ascii.colors[0], [1.0, 0.0, 0.0, 1.0]);
    assert!((ascii.colors[1][3] - 128.0 / 255.0).abs() < 1e-6);
    assert!((ascii.colors[3][0] - srgb_to_linear(10.0 / 255.0)).abs() < 1e-7);
    assert_eq!(ascii.surfaces[0].texture_file(), Some("skin.png"));
}

#[test]
fn truncated_binary_files_are_errors_at_every_cut() {
    for format in [Format::Le, Format::Be] {
        let full = sample(format);
        assert!(parse(&full).is_ok());
        let header_end = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        let cuts = [
            0,
            3,
            header_end - 5,
            header_end,
            header_end + 1,
            header_end + 44,
            header_end + 150,
            full.len() - 13,
            full.len() - 1,
        ];
        for cut in cuts {
            let err = parse(&full[..cut]).expect_err("a cut file must not import");
            assert!(
                matches!(err, ImportError::Truncated { .. }),
                "cut at {cut}: {err}"
            );
        }
    }
}

#[test]
fn truncated_ascii_is_an_error() {
    let full = sample(Format::Ascii);
    for cut in [full.len() - 4, full.len() - 30, full.len() / 2] {
        let err = parse(&full[..cut]).expect_err("a cut file must not import");
        assert!(
            matches!(
                err,
                ImportError::Truncated { .. } | ImportError::Malformed { .. }
            ),
            "{err}"
        );
    }
}

/// A binary little-endian triangle whose vertex 1 has coordinate y = `y`.
fn triangle_with_y(y: f32) -> Vec<u8> {
    let mut out = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
                    property float x\nproperty float y\nproperty float z\nelement face 1\n\
                    property list uchar uint vertex_indices\nend_header\n"
        .to_vec();
    for v in [0.0, 0.0, 0.0, 1.0, y, 0.0, 0.0, 1.0, 0.0f32] {
        out.extend_from_slice(&v.to_le_bytes());
    }
    out.push(3);
    for i in 0..3u32 {
        out.extend_from_slice(&i.to_le_bytes());
    }
    out
}

#[test]
fn non_finite_coordinates_are_named() {
    assert!(parse(&triangle_with_y(0.0)).is_ok());
    let err = parse(&triangle_with_y(f32::NAN)).unwrap_err().to_string();
    assert_eq!(err, "t.ply: vertex 1: coordinate y is NaN");
    let err = parse(&triangle_with_y(f32::NEG_INFINITY))
        .unwrap_err()
        .to_string();
    assert_eq!(err, "t.ply: vertex 1: coordinate y is -inf");
    // An ascii file says the same as the binary one.
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                end_header\n0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n";
    let err = parse(text.as_bytes()).unwrap_err().to_string();
    assert_eq!(err, "t.ply: vertex 1: coordinate y is NaN");
    let err = parse(text.replace("nan", "-inf").as_bytes())
        .unwrap_err()
        .to_string();
    assert_eq!(err, "t.ply: vertex 1: coordinate y is -inf");
}

/// The ascii triangle of `non_finite_coordinates_are_named` with its data lines replaced.
fn ascii_triangle(data: &str) -> Vec<u8> {
    format!(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
         end_header\n{data}"
    )
    .into_bytes()
}

#[test]
fn ascii_errors_name_element_line_and_property() {
    let ok = parse(&ascii_triangle("0 0 0\n1. 0 .5\n\n0 1 0\n3 0 1 2\n")).unwrap();
    assert_eq!(ok.positions[1], [1.0, 0.0, 0.5]);
    let err = |data: &str| parse(&ascii_triangle(data)).unwrap_err().to_string();
    assert_eq!(
        err("0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n"),
        "t.ply: vertex 1 (line 11): property 'y': 'x'; expected a float"
    );
    assert_eq!(
        err("0 0 0\n1 0\n0 1 0\n3 0 1 2\n"),
        "t.ply: vertex 1 (line 11): property 'z': the line ends after 2 values; expected a float"
    );
    assert_eq!(
        err("0 0 0\n1 0 0 0 1 0\n3 0 1 2\n"),
        "t.ply: vertex 1 (line 11): 3 values after the last property; expected 3 (two lines \
         run together?)"
    );
    assert_eq!(
        err("0 0 0\n1 0 0\n0 1 0\n300 0 1 2\n"),
        "t.ply: face 0 (line 13): property 'vertex_indices': '300'; expected a uchar (0 to 255)"
    );
    assert_eq!(
        err("0 0 0\n1 0 0\n0 1 0\n"),
        "t.ply: truncated: face 0: the file ends after 0 of the 1 'face' lines the header \
         declares; expected 1 more"
    );
    assert_eq!(
        err("0 0 0\n1 0 0\n0 1 0\n3 0 1"),
        "t.ply: truncated: face 0 (line 13): the file ends in the middle of it (property \
         'vertex_indices': the line ends after 3 values; expected 3 list values); expected a \
         complete last line"
    );
}

#[test]
fn index_out_of_range_is_named() {
    let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 7\n";
    let err = parse(text.as_bytes()).unwrap_err().to_string();
    assert_eq!(
        err,
        "t.ply: face 1: vertex index 7 out of range (3 vertices)"
    );
    let neg = text.replace("3 0 1 7", "3 0 -1 2");
    let err = parse(neg.as_bytes()).unwrap_err().to_string();
    assert_eq!(
        err,
        "t.ply: face 1: vertex index -1 out of range (3 vertices)"
    );
}

#[test]
fn tristrips_are_decoded_with_restarts() {
    let text = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n\
                property float z\nelement tristrips 1\nproperty list int int vertex_indices\n\
                end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 0 0\n2 1 0\n\
                9 0 1 2 3 -1 1 4 3 5\n";
    let mut report = ImportReport::default();
    let mesh = parse_ply(&src(), text.as_bytes(), &mut report).unwrap();
    let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.position).collect();
    assert_eq!(tris, vec![[0, 1, 2], [2, 1, 3], [1, 4, 3], [3, 4, 5]]);
    // Every triangle faces +z (counter-clockwise seen from above).
    for [a, b, c] in tris {
        let (a, b, c) = (
            mesh.positions[a as usize],
            mesh.positions[b as usize],
            mesh.positions[c as usize],
        );
        let z = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(z > 0.0);
    }
    // A joint (repeated index) is dropped and noted.
    let joint = text.replace("9 0 1 2 3 -1 1 4 3 5", "6 0 1 2 2 3 4");
    let mesh = parse_ply(&src(), joint.as_bytes(), &mut report).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
    assert!(
        report.notes.iter().any(|n| n.contains("2 degenerate")),
        "{:?}",
        report.notes
    );
}

#[test]
fn per_corner_texcoords_make_seams() {
    let text = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                property list uchar float texcoord\nend_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n\
                3 0 1 2 6 0 0 1 0 0 1\n3 2 1 3 6 0.5 0.5 0.25 0.25 1 1\n";
    let mesh = parse(text.as_bytes()).unwrap();
    assert_eq!(mesh.uvs.len(), 6);
    assert_eq!(mesh.triangles[1].uv, [3, 4, 5]);
    assert_eq!(mesh.uvs[3], [0.5, 0.5]);
    let bad = text.replace("6 0.5 0.5 0.25 0.25 1 1", "4 0.5 0.5 0.25 0.25");
    let err = parse(bad.as_bytes()).unwrap_err().to_string();
    assert!(
        err.contains("face 1: 4 texcoord values for 3 vertices"),
        "{err}"
    );
}

#[test]
fn malformed_headers_are_errors() {
    let err = |t: &str| parse(t.as_bytes()).unwrap_err().to_string();
    assert!(err("ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n")
        .contains("no 'vertex' element"));
    assert!(err("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n")
        .contains("no 'z' property"));
    assert!(err("ply\nformat binary_little_endian 1.0\nelement vertex 1\nelement junk 4000000000000\nend_header\n")
        .contains("no properties"));
    assert!(
        err("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n").contains("truncated")
    );
    assert!(err("not a ply").contains("header"));
    assert!(err("ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n1 0 0 0\n")
        .contains("property 'x' is a list"));
    assert!(err("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar float vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
        .contains("element 'face'"));
    // A huge count in a small binary file is caught before parsing.
    let huge = "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\n\
                property float x\nproperty float y\nproperty float z\nend_header\n";
    let e = err(huge);
    assert!(
        e.contains("truncated") && e.contains("4000000000000 x 'vertex'"),
        "{e}"
    );
}

/// `bytes` (a binary file in a layout the direct reader takes) read by the direct reader and
/// by the parser's, each as its mesh or its error's message.
fn both_readers(bytes: &[u8]) -> [Result<Mesh, String>; 2] {
    let source = src();
    let (mut reader, header) = read_header(&source, bytes).unwrap();
    let present = Present::check(&source, &header).unwrap();
    let start = reader.get_ref().position() as usize;
    let payload = binary::Payload::find(&header, &bytes[start..]).expect("a direct layout");
    let mut report = ImportReport::default();
    let direct = read_direct(&source, &payload, &header, present, &mut report);
    let mut report = ImportReport::default();
    let parsed = read_parsed(&source, bytes, &mut reader, &header, present, &mut report);
    [direct, parsed].map(|r| r.map_err(|e| e.to_string()))
}

#[test]
fn the_direct_reader_gives_the_parsers_mesh_and_errors() {
    // Byte colours and a scalar after the faces' index list, in both byte orders.
    for format in [Format::Le, Format::Be] {
        let [direct, parsed] = both_readers(&sample(format));
        assert_eq!(direct.unwrap(), parsed.unwrap());
    }
    // A non-finite value and an index out of range: the same error.
    let [direct, parsed] = both_readers(&triangle_with_y(f32::NAN));
    assert_eq!(direct.unwrap_err(), parsed.unwrap_err());
    let mut bad_index = triangle_with_y(0.0);
    let last = bad_index.len() - 4;
    bad_index[last..].copy_from_slice(&9u32.to_le_bytes());
    let [direct, parsed] = both_readers(&bad_index);
    let error = direct.unwrap_err();
    assert_eq!(
        error,
        "t.ply: face 0: vertex index 9 out of range (3 vertices)"
    );
    assert_eq!(error, parsed.unwrap_err());
}

#[test]
fn other_layouts_and_cut_payloads_are_left_to_the_parser() {
    let layout = |bytes: &[u8]| {
        let (reader, header) = read_header(&src(), bytes).unwrap();
        let start = reader.get_ref().position() as usize;
        binary::Payload::find(&header, &bytes[start..]).is_some()
    };
    let full = triangle_with_y(0.0);
    assert!(layout(&full));
    // A cut list: the parser's reader names it.
    assert!(!layout(&full[..full.len() - 1]));
    let ascii = ascii_triangle("0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert!(!layout(&ascii));
    let texcoord = String::from_utf8_lossy(&full).replace(
        "vertex_indices\n",
        "vertex_indices\nproperty list uchar float texcoord\n",
    );
    assert!(!layout(texcoord.as_bytes()));
}

/// A binary grid of `side` x `side` vertices with byte colours (every channel value) and
/// ushort alpha, and two triangles per cell, each face's index list its only property: the
/// layout whose vertices and triangles the direct reader converts in pieces on all cores.
fn grid(side: u32) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_big_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nproperty ushort alpha\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        side * side,
        2 * (side - 1) * (side - 1)
    )
    .into_bytes();
    for v in 0..side * side {
        for c in [v % side, v / side, v % 7] {
            out.extend_from_slice(&(c as f32).to_be_bytes());
        }
        out.extend_from_slice(&[v as u8, (v / 3) as u8, 255 - v as u8]);
        out.extend_from_slice(&((v * 13) as u16).to_be_bytes());
    }
    for y in 0..side - 1 {
        for x in 0..side - 1 {
            let v = (y * side + x) as i32;
            let s = side as i32;
            for t in [[v, v + 1, v + s], [v + 1, v + s + 1, v + s]] {
                out.push(3);
                for i in t {
                    out.extend_from_slice(&i.to_be_bytes());
                }
            }
        }
    }
    out
}

#[test]
fn pieces_on_all_cores_give_the_parsers_mesh_and_first_errors() {
    let side = 150u32;
    let bytes = grid(side);
    let [direct, parsed] = both_readers(&bytes);
    let mesh = direct.unwrap();
    assert_eq!(mesh.positions.len(), (side * side) as usize);
    assert_eq!(mesh.triangles.len(), (2 * (side - 1) * (side - 1)) as usize);
    assert_eq!(mesh, parsed.unwrap());
    // The colours of the table are those of the conversion, channel for channel.
    for (v, c) in mesh.colors.iter().enumerate() {
        let byte = byte_colour(v % 256);
        assert_eq!(c[0].to_bits(), srgb_to_linear(byte).to_bits(), "vertex {v}");
    }
    let header_len = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    let vertex_len = 3 * 4 + 3 + 2;
    let face_len = 1 + 3 * 4;
    let faces_at = header_len + (side * side) as usize * vertex_len;
    // Two bad vertices in different pieces: the first is named, by both readers.
    let mut bad = bytes.clone();
    for v in [15_000usize, 9_000] {
        let at = header_len + v * vertex_len + 4;
        bad[at..at + 4].copy_from_slice(&f32::INFINITY.to_be_bytes());
    }
    let [direct, parsed] = both_readers(&bad);
    let error = direct.unwrap_err();
    assert!(error.contains("vertex 9000"), "{error}");
    assert_eq!(error, parsed.unwrap_err());
    // Two faces with an index out of range: the first is named.
    let mut bad = bytes.clone();
    for (f, index) in [(40_000usize, -3i32), (12_000, 999_999)] {
        let at = faces_at + f * face_len + 1 + 4;
        bad[at..at + 4].copy_from_slice(&index.to_be_bytes());
    }
    let [direct, parsed] = both_readers(&bad);
    let error = direct.unwrap_err();
    assert_eq!(
        error,
        "t.ply: face 12000: vertex index 999999 out of range (22500 vertices)"
    );
    assert_eq!(error, parsed.unwrap_err());
}
