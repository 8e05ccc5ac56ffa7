//! `caveclod info` lists a file's materials and says whether it has vertex colours, in text
//! and as JSON; `caveclod export` writes the MTL file and the embedded textures beside the
//! OBJ.

mod common;

use std::path::Path;

use caveclod_bake::mesh::{AlphaMode, Surface, Texture};
use caveclod_bake::pipeline::bake_mesh;
use caveclod_tests::{meshes, to_mesh};
use common::{caveclod, s, stdout, succeeded};
use serde_json::json;

/// A two-surface terrain with a texture file ("tex/rock.png" in `dir`) and an embedded
/// image, written to `dir/terrain.clod`.
fn write_clod(dir: &Path) -> std::path::PathBuf {
    let mut mesh = to_mesh(&meshes::terrain(8, 8, 1));
    mesh.surfaces = vec![
        Surface {
            texture: Some(Texture::File("tex/rock.png".into())),
            alpha: AlphaMode::Mask { cutoff: 0.5 },
            double_sided: true,
            ..Surface::plain("Rock")
        },
        Surface {
            base_color: [0.2, 0.5, 1.0, 0.5],
            texture: Some(Texture::Embedded {
                mime: "image/jpeg".into(),
                bytes: vec![0xff, 0xd8, 0xff, 0xe0, 1, 2, 3],
            }),
            alpha: AlphaMode::Blend,
            ..Surface::plain("Water")
        },
    ];
    let (mut baked, _) = bake_mesh(&mesh, "terrain", &mut |_| {}).expect("bake");
    baked.texture_dir = dir.to_path_buf();
    let path = dir.join("terrain.clod");
    baked.write(&path, &[]).expect("write");
    path
}

#[test]
fn info_lists_materials() {
    let dir = tempfile::tempdir().unwrap();
    let clod = write_clod(dir.path());
    let file = clod.to_str().unwrap();
    let report = common::json(&caveclod(&["info", "--json", file]));
    assert_eq!(
        report["materials"],
        json!([
            {
                "name": "Rock",
                "base_colour": [1.0, 1.0, 1.0, 1.0],
                "texture": {"path": "tex/rock.png"},
                "alpha_mode": "MASK",
                "alpha_cutoff": 0.5,
                "double_sided": true,
            },
            {
                "name": "Water",
                "base_colour": [0.2, 0.5, 1.0, 0.5],
                "texture": {"embedded_bytes": 7, "mime": "image/jpeg"},
                "alpha_mode": "BLEND",
                "alpha_cutoff": null,
                "double_sided": false,
            },
        ])
    );
    assert_eq!(report["vertex_colours"], json!(false));
    let text = stdout(&caveclod(&["info", file]));
    assert!(text.contains("material 0: 'Rock'"), "{text}");
    assert!(
        text.contains("texture tex/rock.png, MASK 0.5, double-sided"),
        "{text}"
    );
    assert!(
        text.contains("embedded image/jpeg, 7 bytes, BLEND"),
        "{text}"
    );
}

#[test]
fn info_of_a_file_without_materials() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plain.clod");
    let bytes = caveclod_tests::bake(&meshes::terrain(6, 6, 1)).to_bytes();
    std::fs::write(&path, &bytes[..]).unwrap();
    let report = common::json(&caveclod(&["info", "--json", s(&path)]));
    assert_eq!(report["materials"], json!([]));
    assert_eq!(report["vertex_colours"], json!(false));
}

#[test]
fn export_writes_the_library_beside_the_obj() {
    let dir = tempfile::tempdir().unwrap();
    let clod = write_clod(dir.path());
    let obj = dir.path().join("out/terrain.obj");
    std::fs::create_dir_all(obj.parent().unwrap()).unwrap();
    succeeded(&caveclod(&["export", s(&clod), "-o", s(&obj)]));
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.contains("mtllib terrain.mtl"));
    assert!(text.contains("usemtl Rock") && text.contains("usemtl Water"));
    let mtl = std::fs::read_to_string(dir.path().join("out/terrain.mtl")).unwrap();
    assert!(
        mtl.contains("newmtl Rock\nKd 1 1 1\nd 1\nmap_Kd ../tex/rock.png"),
        "{mtl}"
    );
    assert!(
        mtl.contains("newmtl Water\nKd 0.2 0.5 1\nd 0.5\nmap_Kd terrain_Water.jpg"),
        "{mtl}"
    );
    assert_eq!(
        std::fs::read(dir.path().join("out/terrain_Water.jpg")).unwrap(),
        [0xff, 0xd8, 0xff, 0xe0, 1, 2, 3]
    );
}
