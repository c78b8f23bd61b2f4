//! CGNS writer (`DIR/mesh.cgns`, cargo feature `cgns`): one structured zone per block
//! (`block_NNNN`, vertex size `[ni + 1, nj + 1]`), coordinates `CoordinateX`/`CoordinateY`
//! (double precision, i fastest), a `GridConnectivity1to1_t` for every interface side (both
//! blocks of an interface carry one, named `block_NNNN_SIDE`, with the ranges and transform of
//! [`crate::connectivity::Cgns1to1`]) and a `BCWall` boundary condition for every wall side
//! (`wall_circle_N_SIDE`; the bounding circle's sides are `bounding_circle_SIDE`), as a
//! 1-based `PointRange`.
//!
//! It links the system CGNS C library (`apt-get install libcgns-dev`) through a small
//! hand-written `extern "C"` block; the declarations assume a library built with 32-bit
//! `cgsize_t` (`CG_BUILD_64BIT 0`, as Debian's `libcgns-dev` 3.4 is).

use super::check_mesh;
use crate::connectivity::{connectivity, SideKind, SIDE_NAMES};
use crate::mesh::Mesh;
use std::ffi::{c_char, c_int, CStr, CString};
use std::io;
use std::path::Path;

/// CGNS's `cgsize_t` for a library built without `CG_BUILD_64BIT`.
type CgSize = i32;

const CG_MODE_WRITE: c_int = 1;
const REAL_DOUBLE: c_int = 4;
const STRUCTURED: c_int = 2;
const POINT_RANGE: c_int = 4;
const BC_WALL: c_int = 20;

#[link(name = "cgns")]
extern "C" {
    fn cg_open(filename: *const c_char, mode: c_int, fn_: *mut c_int) -> c_int;
    fn cg_close(fn_: c_int) -> c_int;
    fn cg_base_write(
        fn_: c_int,
        basename: *const c_char,
        cell_dim: c_int,
        phys_dim: c_int,
        b: *mut c_int,
    ) -> c_int;
    fn cg_zone_write(
        fn_: c_int,
        b: c_int,
        zonename: *const c_char,
        size: *const CgSize,
        zone_type: c_int,
        z: *mut c_int,
    ) -> c_int;
    fn cg_coord_write(
        fn_: c_int,
        b: c_int,
        z: c_int,
        data_type: c_int,
        coordname: *const c_char,
        coord: *const std::ffi::c_void,
        c: *mut c_int,
    ) -> c_int;
    fn cg_1to1_write(
        fn_: c_int,
        b: c_int,
        z: c_int,
        connectname: *const c_char,
        donorname: *const c_char,
        range: *const CgSize,
        donor_range: *const CgSize,
        transform: *const c_int,
        i: *mut c_int,
    ) -> c_int;
    fn cg_boco_write(
        fn_: c_int,
        b: c_int,
        z: c_int,
        boconame: *const c_char,
        bocotype: c_int,
        ptset_type: c_int,
        npnts: CgSize,
        pnts: *const CgSize,
        bc: *mut c_int,
    ) -> c_int;
    fn cg_get_error() -> *const c_char;
}

/// Turn a CGNS status into an `io::Result`, with the library's message.
fn check(status: c_int, what: &str) -> io::Result<()> {
    if status == 0 {
        return Ok(());
    }
    // SAFETY: cg_get_error returns a pointer to a static NUL-terminated buffer (or null).
    let msg = unsafe {
        let p = cg_get_error();
        if p.is_null() {
            String::new()
        } else {
            CStr::from_ptr(p).to_string_lossy().into_owned()
        }
    };
    Err(io::Error::other(format!("CGNS {what} failed: {msg}")))
}

fn cstr(s: &str) -> io::Result<CString> {
    CString::new(s).map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e))
}

fn size(x: usize) -> io::Result<CgSize> {
    CgSize::try_from(x).map_err(|_| io::Error::other("mesh too large for 32-bit CGNS sizes"))
}

/// Write `mesh` as CGNS to `path` (through a temporary file renamed on success).
///
/// Errors: I/O or CGNS library failures, a mesh whose grids do not match its blocks, or an
/// invalid connectivity (`InvalidInput`).
pub fn write_cgns(mesh: &Mesh, path: &Path) -> io::Result<()> {
    check_mesh(mesh)?;
    let conn = connectivity(&mesh.layout, &mesh.grids)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidInput, e.to_string()))?;
    let name = path
        .file_name()
        .ok_or_else(|| io::Error::new(io::ErrorKind::InvalidInput, "not a file path"))?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(".tmp");
    let tmp = path.with_file_name(tmp_name);
    let _ = std::fs::remove_file(&tmp);
    let tmp_c = cstr(
        tmp.to_str()
            .ok_or_else(|| io::Error::other("output path is not UTF-8"))?,
    )?;
    let mut f: c_int = 0;
    // SAFETY: valid NUL-terminated path and out-pointer.
    check(
        unsafe { cg_open(tmp_c.as_ptr(), CG_MODE_WRITE, &mut f) },
        "open",
    )?;
    let body = write_body(f, mesh, &conn);
    // SAFETY: f is an open CGNS file.
    let closed = check(unsafe { cg_close(f) }, "close");
    let result = body
        .and(closed)
        .and_then(|()| super::replace_file(&tmp, path));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

fn write_body(
    f: c_int,
    mesh: &Mesh,
    conn: &[crate::connectivity::BlockConnectivity],
) -> io::Result<()> {
    let base_name = cstr("medial_blocks")?;
    let mut b: c_int = 0;
    // SAFETY: open file, valid strings and out-pointers throughout.
    check(
        unsafe { cg_base_write(f, base_name.as_ptr(), 2, 2, &mut b) },
        "base_write",
    )?;
    let zone_name = |k: usize| format!("block_{k:04}");
    for (k, (g, bc)) in mesh.grids.iter().zip(conn).enumerate() {
        let dims = [
            size(g.ni + 1)?,
            size(g.nj + 1)?,
            size(g.ni)?,
            size(g.nj)?,
            0,
            0,
        ];
        let zn = cstr(&zone_name(k))?;
        let mut z: c_int = 0;
        check(
            unsafe { cg_zone_write(f, b, zn.as_ptr(), dims.as_ptr(), STRUCTURED, &mut z) },
            "zone_write",
        )?;
        for (axis, cname) in ["CoordinateX", "CoordinateY"].iter().enumerate() {
            let values: Vec<f64> = g.nodes.iter().map(|p| p[axis]).collect();
            let cn = cstr(cname)?;
            let mut c: c_int = 0;
            check(
                unsafe {
                    cg_coord_write(
                        f,
                        b,
                        z,
                        REAL_DOUBLE,
                        cn.as_ptr(),
                        values.as_ptr().cast(),
                        &mut c,
                    )
                },
                "coord_write",
            )?;
        }
        for sc in &bc.sides {
            if let (Some(p), Some(c)) = (sc.partner, sc.cgns) {
                let name = cstr(&format!("{}_{}", zone_name(k), sc.name))?;
                let donor = cstr(&zone_name(p.block))?;
                let r = flat(c.point_range)?;
                let d = flat(c.point_range_donor)?;
                let t: [c_int; 2] = c.transform;
                let mut i: c_int = 0;
                check(
                    unsafe {
                        cg_1to1_write(
                            f,
                            b,
                            z,
                            name.as_ptr(),
                            donor.as_ptr(),
                            r.as_ptr(),
                            d.as_ptr(),
                            t.as_ptr(),
                            &mut i,
                        )
                    },
                    "1to1_write",
                )?;
            } else if matches!(sc.kind, SideKind::Wall | SideKind::Outer) {
                let label = match (sc.kind, sc.circle) {
                    (SideKind::Outer, _) | (_, Some(-1)) => "bounding_circle".to_string(),
                    (_, Some(id)) => format!("wall_circle_{id}"),
                    (_, None) => "wall".to_string(),
                };
                let name = cstr(&format!("{label}_{}", SIDE_NAMES[sc.side]))?;
                let (ni, nj) = (g.ni + 1, g.nj + 1);
                let range = match sc.side {
                    0 => [[1, 1], [ni, 1]],
                    1 => [[ni, 1], [ni, nj]],
                    2 => [[1, nj], [ni, nj]],
                    _ => [[1, 1], [1, nj]],
                };
                let r = flat(range)?;
                let mut i: c_int = 0;
                check(
                    unsafe {
                        cg_boco_write(
                            f,
                            b,
                            z,
                            name.as_ptr(),
                            BC_WALL,
                            POINT_RANGE,
                            2,
                            r.as_ptr(),
                            &mut i,
                        )
                    },
                    "boco_write",
                )?;
            }
        }
    }
    Ok(())
}

fn flat(r: [[usize; 2]; 2]) -> io::Result<[CgSize; 4]> {
    Ok([
        size(r[0][0])?,
        size(r[0][1])?,
        size(r[1][0])?,
        size(r[1][1])?,
    ])
}
