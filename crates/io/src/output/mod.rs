//! Plain output formats: CSV, JSON, Matrix Market, NumPy `.npz` and OBJ. Every writer goes through
//! [`crate::atomic::write_atomic`].

mod csv;
mod json;
mod matrix_market;
mod npz;
mod obj;

pub use csv::{format_f64, write_csv, write_csv_text};
pub use json::write_json;
pub use matrix_market::{
    read_matrix_market, read_matrix_market_array, write_matrix_market, write_matrix_market_array,
    write_matrix_market_symmetric, write_matrix_market_vector,
};
pub use npz::{NpyArray, NpyData, crc32, npz_bytes, write_npz};
pub use obj::{ObjMesh, read_obj, write_obj};
