use super::*;

fn src() -> Source {
    Source {
        name: "m.obj".to_owned(),
    }
}

fn parse_with(
    obj: &str,
    files: &[(&str, &str)],
    report: &mut ImportReport,
) -> Result<Mesh, ImportError> {
    let files: HashMap<String, Vec<u8>> = files
        .iter()
        .map(|(n, t)| (n.to_string(), t.as_bytes().to_vec()))
        .collect();
    let mut load = |name: &str| {
        files
            .get(name)
            .cloned()
            .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::NotFound, "not found"))
    };
    parse_obj(&src(), obj.as_bytes(), &mut load, report)
}

fn parse(obj: &str) -> Result<Mesh, ImportError> {
    parse_with(obj, &[], &mut ImportReport::default())
}

#[test]
fn corners_keep_their_own_indices() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\nvt 0.5 0.5\n\
               vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 3/5/1 2/2 4/4/1\nf 1 2 4\n";
    let mesh = parse(obj).unwrap();
    mesh.validate().unwrap();
    assert_eq!(mesh.triangles.len(), 3);
    assert_eq!(mesh.triangles[1].position, [2, 1, 3]);
    assert_eq!(mesh.triangles[1].uv, [4, 1, 3]);
    assert_eq!(mesh.triangles[1].normal, [0, NO_ATTRIBUTE, 0]);
    assert_eq!(mesh.triangles[2].uv, [NO_ATTRIBUTE; 3]);
    assert_eq!(mesh.uvs[2], [0.0, 0.0], "v is flipped");
    assert_eq!(mesh.surfaces.len(), 1);
    assert_eq!(mesh.surfaces[0].name, "default");
}

#[test]
fn polygons_relative_indices_and_continuations() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0 \\\n\nv 0 1 0\nv -1 0.5 0 2\nf -5 -4 -3 -2 \\\n -1\n";
    let mesh = parse(obj).unwrap();
    let tris: Vec<[u32; 3]> = mesh.triangles.iter().map(|t| t.position).collect();
    assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    assert_eq!(mesh.positions[4], [-0.5, 0.25, 0.0], "w divides");
}

#[test]
fn vertex_colours_are_per_position() {
    let obj = "v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n";
    let mesh = parse(obj).unwrap();
    assert_eq!(mesh.colors.len(), 2);
    assert_eq!(mesh.triangles[0].color, [0, NO_ATTRIBUTE, 1]);
    assert_eq!(mesh.colors[1], [0.0, 0.0, 1.0, 1.0]);
}

#[test]
fn errors_name_the_line() {
    let head = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\n";
    let err = |tail: &str| parse(&format!("{head}{tail}")).unwrap_err().to_string();
    assert_eq!(
        err("f 1 2 3\nf 1 2 4\n"),
        "m.obj: line 6: vertex index 4 out of range (3 positions)"
    );
    assert_eq!(
        err("f 1/1 2/2 3/1\n"),
        "m.obj: line 5: texture coordinate index 2 out of range (1 texture coordinates)"
    );
    assert_eq!(
        err("f 1//1 2//1 3//1\n"),
        "m.obj: line 5: normal index 1 out of range (0 normals)"
    );
    assert_eq!(
        err("f -4 1 2\n"),
        "m.obj: line 5: vertex index -4 out of range (3 positions)"
    );
    assert!(err("f 1/0 2/1 3/1\n").contains("line 5: face corner '1/0': index 0"));
    assert!(err("f 1 2 x\n").contains("line 5: face corner 'x'"));
    assert!(err("f 1/1/1/1 2 3\n").contains("more than three indices"));
    assert_eq!(err("v 1 nan 0\n"), "m.obj: line 5: coordinate y is NaN");
    assert_eq!(err("vn 1 0 inf\n"), "m.obj: line 5: normal z is inf");
    assert!(err("v 1 2\n").contains("line 5: v needs 3, 4, 6 or 7 numbers, found 2"));
    assert!(err("v 1 2 3 0\n").contains("line 5: vertex weight w is 0"));
    assert!(err("vt 1 abc\n").contains("line 5: vt: 'abc' is not a number"));
    // A forward reference resolves once the vertex exists.
    assert!(parse(&format!("{head}f 1 2 4\nv 1 1 0\n")).is_ok());
}

#[test]
fn points_and_lines_are_skipped_and_counted() {
    let mut report = ImportReport::default();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\nl 1 2\nf 1 2\nf 1 2 3\ncurv 0 1 1 2\n";
    let mesh = parse_with(obj, &[], &mut report).unwrap();
    assert_eq!(mesh.triangles.len(), 1);
    assert_eq!(report.skipped_primitives, 3);
    assert!(
        report.notes.iter().any(|n| n.contains("'curv'")),
        "{:?}",
        report.notes
    );
}

#[test]
fn materials_become_surfaces_in_order_of_use() {
    let mtl = "newmtl red\nKd 1 0 0\nd 0.5\nmap_Kd -s 1 1 1 tex/red.png\n\
               newmtl grey\nKd 0.5\nnewmtl unused\nKd 0 1 0\n";
    let obj = "mtllib lib/m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl grey\nf 1 2 3\n\
               usemtl red\nf 1 3 2\nusemtl grey\nf 2 1 3\nusemtl ghost\nf 3 2 1\n";
    let mut report = ImportReport::default();
    let mesh = parse_with(obj, &[("lib/m.mtl", mtl)], &mut report).unwrap();
    let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["grey", "red", "ghost"]);
    assert_eq!(mesh.surfaces[0].base_color, [0.5, 0.5, 0.5, 1.0]);
    assert_eq!(mesh.surfaces[1].base_color, [1.0, 0.0, 0.0, 0.5]);
    assert_eq!(mesh.surfaces[1].texture_file(), Some("lib/tex/red.png"));
    // `d` below 1 blends; opaque otherwise.
    assert_eq!(mesh.surfaces[1].alpha, crate::mesh::AlphaMode::Blend);
    assert_eq!(mesh.surfaces[0].alpha, crate::mesh::AlphaMode::Opaque);
    assert_eq!(mesh.surfaces[2].base_color, [1.0; 4]);
    assert!(mesh.surfaces[2].is_plain());
    let ids: Vec<u16> = mesh.triangles.iter().map(|t| t.surface).collect();
    assert_eq!(ids, [0, 1, 0, 2]);
    assert!(
        report.notes.iter().any(|n| n.contains("'ghost'")),
        "{:?}",
        report.notes
    );
}

#[test]
fn missing_mtl_keeps_material_names() {
    let obj = "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 1 3 2\n";
    let mut report = ImportReport::default();
    let mesh = parse_with(obj, &[], &mut report).unwrap();
    let names: Vec<&str> = mesh.surfaces.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["a", "b"]);
    assert!(report
        .notes
        .iter()
        .any(|n| n.contains("'gone.mtl' cannot be read")));
}

#[test]
fn malformed_mtl_names_its_line() {
    let obj = "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let mut report = ImportReport::default();
    let err = parse_with(obj, &[("m.mtl", "newmtl a\nKd 1 0\n")], &mut report)
        .unwrap_err()
        .to_string();
    assert_eq!(err, "m.obj: m.mtl line 2: Kd needs 1 or 3 numbers");
    let err = parse_with(obj, &[("m.mtl", "newmtl a\nNs 1\nillum x\n")], &mut report)
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("m.obj: m.mtl line 3: "), "{err}");
}

#[test]
fn a_last_line_cut_off_is_an_error_naming_it() {
    let tri = "v 0 0 0\nv 1 0 0\nv 0 0 1\n";
    // A complete last statement without a line break is fine.
    assert_eq!(parse(&format!("{tri}f 1 2 3")).unwrap().triangles.len(), 1);
    let err = parse(&format!("{tri}f 1 2 3\nf 1 2"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "m.obj: truncated: line 5: the file ends in the middle of it (a face with fewer than \
         3 corners); expected a complete last line"
    );
    let err = parse(&format!("{tri}f 1 2 3\nv 1 0"))
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "m.obj: truncated: line 5: the file ends in the middle of it (v needs 3, 4, 6 or 7 \
         numbers, found 2); expected a complete last line"
    );
    let err = parse(&format!("{tri}f 1 2 3\nusemtl"))
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("m.obj: truncated: line 5: the file ends in the middle of it (usemtl"),
        "{err}"
    );
    // The same face with its line break is a skipped face, counted.
    let mut report = ImportReport::default();
    let mesh = parse_with(&format!("{tri}f 1 2 3\nf 1 2\n"), &[], &mut report).unwrap();
    assert_eq!((mesh.triangles.len(), report.skipped_primitives), (1, 1));
}

#[test]
fn binary_data_is_not_an_obj_file() {
    let err = parse("v 0 0 0\nv 1 0 0\n\u{1}\u{2}garbage\n")
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "m.obj: line 3: byte 0x01 at offset 16 is not text; expected a Wavefront OBJ text file"
    );
    // Tabs, form feeds and carriage returns are text.
    assert!(parse("v 0 0 0\r\nv\t1 0 0\x0c\r\nv 0 0 1\r\nf 1 2 3\r\n").is_ok());
}

#[test]
fn text_that_is_not_obj_names_its_statements() {
    let err = parse("Dear reader,\nthis is a letter.\nDear me.\n")
        .unwrap_err()
        .to_string();
    assert_eq!(
        err,
        "m.obj: no triangles: no face, and unknown statements (2 x 'Dear', 1 x 'this'); \
         expected 'v' and 'f' statements"
    );
}
