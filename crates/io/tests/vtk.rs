//! VTK files written by nurbspring-io, read back with the independent `vtkio` crate; values are
//! compared exactly.

use base64::Engine as _;
use nurbspring_io::vtk::{
    Cell, DataArray, HeaderType, PvdSeries, StringArray, VtkEncoding, VtkFormat, VtkStructured,
    VtkUnstructured,
};
use vtkio::Vtk;
use vtkio::model::{Attribute, CellType, DataSet, Extent, Piece, VertexNumbers};

/// A lattice-like grid with every cell kind and awkward values.
fn sample() -> VtkUnstructured {
    let points = vec![
        [0.0, 0.0, 2.0],
        [0.25, 0.83, 2.0],
        [1.52, 1.0 / 3.0, -1e-300],
        [3.0, 5.0, 2.0],
        [1e300, -0.0, 7.5],
    ];
    let cells = vec![
        Cell::Vertex(4),
        Cell::Line([0, 1]),
        Cell::Triangle([0, 1, 2]),
        Cell::Quad([0, 1, 3, 2]),
        Cell::PolyVertex(vec![2, 3, 4]),
        Cell::PolyLine(vec![0, 2, 4]),
    ];
    let mut g = VtkUnstructured::new(points);
    g.cells = cells;
    g.point_data.push(DataArray::vectors(
        "velocity <v>",
        &[
            [0.0, 0.0, -0.2],
            [0.1, 0.2, 0.3],
            [f64::MIN_POSITIVE, 1.0, 2.0],
            [4.0, 5.0, 6.0],
            [7.0, 8.0, 9.0],
        ],
    ));
    g.point_data
        .push(DataArray::scalars("mass", vec![0.005; 5]));
    g.cell_data.push(DataArray::scalars(
        "k",
        vec![0.0, 2.7225, 0.8661, 1.0, 2.0, 3.0],
    ));
    g.cell_data.push(DataArray::new(
        "pair",
        2,
        (0..12).map(|k| k as f64 * 0.1).collect(),
    ));
    g
}

/// Reads a `.vtu` back and checks every value against `g`.
fn check_vtu(path: &std::path::Path, g: &VtkUnstructured) {
    let vtk =
        Vtk::import(path).unwrap_or_else(|e| panic!("vtkio cannot read {}: {e:?}", path.display()));
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        panic!("not an unstructured grid")
    };
    assert_eq!(pieces.len(), 1);
    let Piece::Inline(piece) = &pieces[0] else {
        panic!("piece not inline")
    };
    let pts: Vec<f64> = piece.points.clone().into_vec().expect("Float64 points");
    let want: Vec<f64> = g.points.iter().flatten().copied().collect();
    assert_eq!(bits(&pts), bits(&want));
    let VertexNumbers::XML {
        connectivity,
        offsets,
    } = &piece.cells.cell_verts
    else {
        panic!("legacy cell numbering")
    };
    let conn: Vec<u64> = g
        .cells
        .iter()
        .flat_map(|c| c.points().iter().map(|&k| k as u64))
        .collect();
    assert_eq!(connectivity, &conn);
    let mut end = 0;
    let offs: Vec<u64> = g
        .cells
        .iter()
        .map(|c| {
            end += c.points().len() as u64;
            end
        })
        .collect();
    assert_eq!(offsets, &offs);
    let types: Vec<u8> = piece.cells.types.iter().map(|t| *t as u8).collect();
    assert_eq!(types, vec![1, 3, 5, 9, 2, 4]);
    assert_eq!(piece.cells.types[3], CellType::Quad);
    compare_attributes(&piece.data.point, &g.point_data);
    compare_attributes(&piece.data.cell, &g.cell_data);
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

fn compare_attributes(read: &[Attribute], written: &[DataArray]) {
    assert_eq!(read.len(), written.len());
    for (r, w) in read.iter().zip(written) {
        let Attribute::DataArray(a) = r else {
            panic!("field attribute")
        };
        assert_eq!(a.name, w.name);
        assert_eq!(a.elem.num_comp() as usize, w.components, "{}", w.name);
        let values: Vec<f64> = a.data.clone().into_vec().expect("Float64 data");
        assert_eq!(bits(&values), bits(&w.values), "{}", w.name);
    }
}

#[test]
fn vtu_binary_uint64_reads_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("lattice.vtu");
    let g = sample();
    g.write(&p).unwrap();
    check_vtu(&p, &g);
}

#[test]
fn vtu_binary_uint32_and_ascii_read_back_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let g = sample();
    let p32 = dir.path().join("h32.vtu");
    g.write_with(
        &p32,
        VtkFormat {
            encoding: VtkEncoding::Binary,
            header: HeaderType::UInt32,
        },
    )
    .unwrap();
    assert!(
        std::fs::read_to_string(&p32)
            .unwrap()
            .contains("header_type=\"UInt32\"")
    );
    check_vtu(&p32, &g);
    // ASCII cannot carry 1e300 through every VTK reader, but vtkio parses Rust's shortest form.
    let pa = dir.path().join("ascii.vtu");
    g.write_with(
        &pa,
        VtkFormat {
            encoding: VtkEncoding::Ascii,
            header: HeaderType::UInt64,
        },
    )
    .unwrap();
    check_vtu(&pa, &g);
}

/// vtkio ignores the byte-count header; check it ourselves: the first 8 (or 4) decoded bytes
/// must be the number of data bytes that follow.
#[test]
fn binary_header_counts_the_data_bytes() {
    let g = sample();
    for (header, size) in [(HeaderType::UInt64, 8usize), (HeaderType::UInt32, 4)] {
        let xml = g
            .to_xml(VtkFormat {
                encoding: VtkEncoding::Binary,
                header,
            })
            .unwrap();
        let mut blocks = 0;
        let mut rest = xml.as_str();
        while let Some(start) = rest.find("format=\"binary\">") {
            let after = &rest[start + "format=\"binary\">".len()..];
            let end = after.find("</DataArray>").unwrap();
            let bytes = base64::engine::general_purpose::STANDARD
                .decode(after[..end].trim())
                .unwrap();
            let mut n = [0u8; 8];
            n[..size].copy_from_slice(&bytes[..size]);
            assert_eq!(u64::from_le_bytes(n) as usize, bytes.len() - size);
            blocks += 1;
            rest = &after[end..];
        }
        // 2 point arrays, 2 cell arrays, points, connectivity, offsets, types.
        assert_eq!(blocks, 8);
    }
}

#[test]
fn invalid_grids_are_refused_without_writing() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("bad.vtu");
    let mut g = sample();
    g.cells.push(Cell::Line([0, 5]));
    let err = g.write(&p).unwrap_err().to_string();
    assert!(err.contains("cell 6 refers to point 5"), "{err}");
    let mut g = sample();
    g.point_data[1].values.pop();
    let err = g.write(&p).unwrap_err().to_string();
    assert!(err.contains("`mass` has 4 values"), "{err}");
    let mut g = sample();
    g.cell_data[1].name = "k".into();
    assert!(g.write(&p).unwrap_err().to_string().contains("used twice"));
    assert!(!p.exists());
}

/// The text between the opening tag of the array named `name` and its `</DataArray>`, with the
/// opening tag itself.
fn array_text<'a>(xml: &'a str, name: &str) -> (&'a str, &'a str) {
    let start = xml
        .find(&format!("Name=\"{name}\""))
        .unwrap_or_else(|| panic!("no array {name}"));
    let open = xml[..start].rfind('<').unwrap();
    let tag_end = start + xml[start..].find('>').unwrap();
    let end = tag_end + xml[tag_end..].find("</DataArray>").unwrap();
    (&xml[open..=tag_end], &xml[tag_end + 1..end])
}

/// String arrays (vtkio reads none, so the bytes are checked here; scripts/check_vtk_strings.py
/// reads them with VTK itself): in binary the byte-count header then each string's UTF-8 bytes
/// and a NUL; in ASCII the same bytes as decimal numbers; `NumberOfTuples` the string count.
#[test]
fn string_arrays_are_encoded_as_vtk_reads_them() {
    let mut g = VtkUnstructured::new(vec![[0.0; 3], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
    g.cells = vec![Cell::Line([0, 1]), Cell::Line([1, 2]), Cell::Line([0, 2])];
    g.cell_data
        .push(DataArray::scalars("kind", vec![0.0, 1.0, 2.0]));
    let names = ["structural", "shear", "bend"].map(String::from).to_vec();
    g.cell_strings.push(StringArray::new("kind_name", names));
    g.point_strings.push(StringArray::new(
        "label",
        vec!["a<b".into(), String::new(), "é".into()],
    ));
    let expected: &[u8] = b"structural\0shear\0bend\0";
    for (header, size) in [(HeaderType::UInt64, 8usize), (HeaderType::UInt32, 4)] {
        let xml = g
            .to_xml(VtkFormat {
                encoding: VtkEncoding::Binary,
                header,
            })
            .unwrap();
        let (tag, body) = array_text(&xml, "kind_name");
        assert!(tag.starts_with("<DataArray type=\"String\""), "{tag}");
        assert!(tag.contains("NumberOfTuples=\"3\""), "{tag}");
        assert!(tag.contains("format=\"binary\""), "{tag}");
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(body.trim())
            .unwrap();
        let mut n = [0u8; 8];
        n[..size].copy_from_slice(&bytes[..size]);
        // 22 bytes, as VTK 9.7's own writer counts these three names.
        assert_eq!(u64::from_le_bytes(n), 22);
        assert_eq!(&bytes[size..], expected);
        // The string array sits in CellData, after the numeric arrays.
        let cell = &xml[xml.find("<CellData>").unwrap()..xml.find("</CellData>").unwrap()];
        assert!(cell.find("Name=\"kind\"").unwrap() < cell.find("Name=\"kind_name\"").unwrap());
        // Point strings: an escaped name-free value, an empty string, two UTF-8 bytes.
        let (_, body) = array_text(&xml, "label");
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(body.trim())
            .unwrap();
        assert_eq!(&bytes[size..], "a<b\0\0é\0".as_bytes());
        assert!(xml[xml.find("<PointData>").unwrap()..].contains("Name=\"label\""));
    }
    let xml = g
        .to_xml(VtkFormat {
            encoding: VtkEncoding::Ascii,
            header: HeaderType::UInt64,
        })
        .unwrap();
    let (tag, body) = array_text(&xml, "kind_name");
    assert!(tag.contains("format=\"ascii\""), "{tag}");
    let codes: Vec<u8> = body
        .split_whitespace()
        .map(|c| c.parse().unwrap())
        .collect();
    assert_eq!(codes, expected);
    assert_eq!(
        body.split_whitespace().take(3).collect::<Vec<_>>(),
        ["115", "116", "114"]
    );
    let (_, body) = array_text(&xml, "label");
    let codes: Vec<u8> = body
        .split_whitespace()
        .map(|c| c.parse().unwrap())
        .collect();
    assert_eq!(codes, "a<b\0\0é\0".as_bytes());
}

#[test]
fn invalid_string_arrays_are_refused() {
    let mut g = sample();
    g.cell_strings
        .push(StringArray::new("kind_name", vec!["x".into(); 5]));
    let err = g.validate().unwrap_err();
    assert!(err.contains("`kind_name` has 5 strings"), "{err}");
    assert!(err.contains("one per cell: 6"), "{err}");
    g.cell_strings[0].values.push("a\0b".into());
    let err = g.validate().unwrap_err();
    assert!(err.contains("string 5 contains a NUL byte"), "{err}");
    g.cell_strings[0].values[5] = "ok".into();
    g.validate().unwrap();
    g.cell_strings[0].name = "k".into();
    assert!(g.validate().unwrap_err().contains("`k` is used twice"));
}

#[test]
fn vts_reads_back_with_u_as_first_index() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("surface.vts");
    let (nu, nv) = (4, 3);
    let pts: Vec<[f64; 3]> = (0..nu)
        .flat_map(|i| {
            (0..nv).map(move |j| {
                [
                    i as f64 / 3.0,
                    2.5 * j as f64,
                    2.0 + 0.01 * (i * nv + j) as f64,
                ]
            })
        })
        .collect();
    let mut g = VtkStructured::new(nu, nv, pts.clone());
    g.point_data.push(DataArray::scalars(
        "k",
        (0..nu * nv).map(|k| k as f64).collect(),
    ));
    g.cell_data.push(DataArray::new(
        "cell",
        2,
        (0..(nu - 1) * (nv - 1))
            .flat_map(|c| [c as f64, -(c as f64)])
            .collect(),
    ));
    g.write(&p).unwrap();
    let vtk = Vtk::import(&p).unwrap();
    let DataSet::StructuredGrid { extent, pieces, .. } = vtk.data else {
        panic!("not a structured grid")
    };
    let Extent::Ranges(r) = extent else {
        panic!("extent")
    };
    assert_eq!(r, [0..=3, 0..=2, 0..=0]);
    let Piece::Inline(piece) = &pieces[0] else {
        panic!()
    };
    let read: Vec<f64> = piece.points.clone().into_vec().unwrap();
    // VTK order: first index (u) fastest.
    for j in 0..nv {
        for i in 0..nu {
            let v = j * nu + i;
            assert_eq!(&read[3 * v..3 * v + 3], &pts[i * nv + j][..]);
        }
    }
    let Attribute::DataArray(k) = &piece.data.point[0] else {
        panic!()
    };
    let kv: Vec<f64> = k.data.clone().into_vec().unwrap();
    assert_eq!(kv[1], 3.0); // VTK point (i=1, j=0) is nurbspring point 1 * n_v + 0
    // vtkio 0.7.0-rc2 counts the cells of a flat extent as (nx-1)(ny-1)(nz-1) = 0 and so drops
    // cell data of 2-D grids; VTK ignores the flat direction. Decode the cell array directly.
    let text = std::fs::read_to_string(&p).unwrap();
    let cell_section = &text[text.find("<CellData>").unwrap()..text.find("</CellData>").unwrap()];
    assert!(cell_section.contains("Name=\"cell\" NumberOfComponents=\"2\""));
    let start = cell_section.find("format=\"binary\">").unwrap() + "format=\"binary\">".len();
    let end = cell_section.find("</DataArray>").unwrap();
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(cell_section[start..end].trim())
        .unwrap();
    assert_eq!(
        u64::from_le_bytes(bytes[..8].try_into().unwrap()),
        6 * 2 * 8
    );
    let cv: Vec<f64> = bytes[8..]
        .chunks(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    // VTK cell (i, j) with i along u fastest is nurbspring cell i * (n_v - 1) + j.
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            let c = (i * (nv - 1) + j) as f64;
            let v = j * (nu - 1) + i;
            assert_eq!(&cv[2 * v..2 * v + 2], &[c, -c]);
        }
    }
    assert!(
        VtkStructured::new(1, 3, vec![[0.0; 3]; 3])
            .write(&p)
            .is_err()
    );
}

#[test]
fn pvd_lists_frames_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("run.pvd");
    let mut s = PvdSeries::default();
    for k in 0..4 {
        s.push(0.08 * k as f64, format!("frames/msm_{k:06}.vtu"));
    }
    s.push(0.32, "a&b.vtu");
    s.write(&p).unwrap();
    let text = std::fs::read_to_string(&p).unwrap();
    assert!(text.contains("<VTKFile type=\"Collection\""));
    let mut frames = Vec::new();
    for line in text.lines().filter(|l| l.contains("<DataSet")) {
        let attr = |name: &str| {
            let start = line.find(&format!("{name}=\"")).unwrap() + name.len() + 2;
            line[start..start + line[start..].find('"').unwrap()].to_string()
        };
        frames.push((attr("timestep").parse::<f64>().unwrap(), attr("file")));
    }
    assert_eq!(frames.len(), 5);
    assert_eq!(frames[3], (0.08 * 3.0, "frames/msm_000003.vtu".to_string()));
    assert_eq!(frames[4].1, "a&amp;b.vtu");
    s.push(f64::NAN, "x.vtu");
    assert!(s.write(&p).is_err());
}
