//! The GSD file layer, version 2.0 (General Simulation Data, the native
//! format of HOOMD-blue, read by OVITO and the Python package `gsd`):
//! frames of named chunks, each an `N × M` array of one element type,
//! written in one piece.
//!
//! The file is, in order:
//!
//! 1. the header, 256 bytes: magic `0x65DF65DF65DF65DF`, the index's
//!    location and entry count, the name list's location and size in
//!    units of 64 bytes (all `u64`), the schema version and the file
//!    layer's version (`u32`, `major << 16 | minor`; here 2.0), the
//!    application and schema names (64 bytes each, NUL-padded) and 80
//!    reserved zero bytes;
//! 2. the chunks' data, one after the other, little-endian;
//! 3. the index, 32 bytes per chunk (`frame: u64`, `N: u64`,
//!    `location: i64`, `M: u32`, name `id: u16`, `type: u8`, `flags: u8 = 0`),
//!    sorted by frame and then by name id, as version 2 readers search it;
//! 4. the name list: the chunk names, each ended by a NUL, ids in order of
//!    first use, padded with NULs to a multiple of 64 bytes.
//!
//! A reader ([`read`]) of exactly this layout checks what the writer
//! wrote; it is not a general GSD reader (no version 1 files).

use crate::error::FormatError;

/// The magic number that opens every GSD file.
pub const MAGIC: u64 = 0x65DF_65DF_65DF_65DF;
/// The file layer version written: 2.0.
pub const VERSION: u32 = 2 << 16;
/// Size of the header, bytes.
pub const HEADER_BYTES: usize = 256;
/// Size of one index entry, bytes.
pub const INDEX_ENTRY_BYTES: usize = 32;
/// The name list is allocated in units of this many bytes.
pub const NAME_UNIT: usize = 64;

/// The element type of a chunk, with the GSD type id it is written as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// `uint8` (id 1).
    U8,
    /// `uint32` (id 3).
    U32,
    /// `uint64` (id 4).
    U64,
    /// `int8` (id 5), also for text.
    I8,
    /// `float32` (id 9).
    F32,
    /// `float64` (id 10).
    F64,
}

impl Kind {
    /// The GSD type id.
    pub fn id(self) -> u8 {
        match self {
            Kind::U8 => 1,
            Kind::U32 => 3,
            Kind::U64 => 4,
            Kind::I8 => 5,
            Kind::F32 => 9,
            Kind::F64 => 10,
        }
    }

    /// Bytes per element.
    pub fn size(self) -> usize {
        match self {
            Kind::U8 | Kind::I8 => 1,
            Kind::U32 | Kind::F32 => 4,
            Kind::U64 | Kind::F64 => 8,
        }
    }

    /// The kind of a GSD type id, if this module writes it.
    pub fn from_id(id: u8) -> Option<Self> {
        [
            Kind::U8,
            Kind::U32,
            Kind::U64,
            Kind::I8,
            Kind::F32,
            Kind::F64,
        ]
        .into_iter()
        .find(|k| k.id() == id)
    }
}

/// One chunk: its name, element type, shape `N × M` (row-major, `M` the
/// fast index) and little-endian bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Chunk {
    /// The chunk's name, e.g. `particles/position`.
    pub name: String,
    /// Element type.
    pub kind: Kind,
    /// Rows.
    pub n: u64,
    /// Columns (at least 1).
    pub m: u32,
    /// `N · M` elements, little-endian.
    pub data: Vec<u8>,
}

impl Chunk {
    /// `values`, `m` to a row, as `float32` (each rounded to the nearest).
    pub fn f32(name: &str, m: u32, values: &[f64]) -> Self {
        let data = values
            .iter()
            .flat_map(|&v| (v as f32).to_le_bytes())
            .collect();
        Self::new(name, Kind::F32, m, values.len(), data)
    }

    /// `values`, `m` to a row, as `float64`.
    pub fn f64(name: &str, m: u32, values: &[f64]) -> Self {
        let data = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        Self::new(name, Kind::F64, m, values.len(), data)
    }

    /// One column of `uint32`.
    pub fn u32(name: &str, values: &[u32]) -> Self {
        let data = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        Self::new(name, Kind::U32, 1, values.len(), data)
    }

    /// One `uint64`.
    pub fn u64(name: &str, value: u64) -> Self {
        Self::new(name, Kind::U64, 1, 1, value.to_le_bytes().to_vec())
    }

    /// One `uint8`.
    pub fn u8(name: &str, value: u8) -> Self {
        Self::new(name, Kind::U8, 1, 1, vec![value])
    }

    /// Strings as the rows of an `int8` matrix, each NUL-terminated and
    /// NUL-padded to the longest plus one (the HOOMD schema's type names
    /// and type shapes).
    pub fn strings(name: &str, rows: &[String]) -> Self {
        let m = rows.iter().map(String::len).max().unwrap_or(0) + 1;
        let mut data = Vec::with_capacity(rows.len() * m);
        for r in rows {
            data.extend_from_slice(r.as_bytes());
            data.resize(data.len() + m - r.len(), 0);
        }
        Self::new(name, Kind::I8, m as u32, rows.len() * m, data)
    }

    fn new(name: &str, kind: Kind, m: u32, elements: usize, data: Vec<u8>) -> Self {
        Self {
            name: name.to_string(),
            kind,
            n: (elements / m as usize) as u64,
            m,
            data,
        }
    }
}

/// A GSD file being put together in memory: frames of chunks.
#[derive(Clone, Debug)]
pub struct Writer {
    application: String,
    schema: String,
    schema_version: (u16, u16),
    frames: Vec<Vec<Chunk>>,
}

impl Writer {
    /// An empty file whose header names `application` and `schema`
    /// (at most 63 bytes each; longer names are cut) and the schema's
    /// version `(major, minor)`.
    pub fn new(application: &str, schema: &str, schema_version: (u16, u16)) -> Self {
        Self {
            application: application.to_string(),
            schema: schema.to_string(),
            schema_version,
            frames: Vec::new(),
        }
    }

    /// Append a frame. Chunk names must be distinct within it, non-empty
    /// and free of NUL; at most 65535 names in the file.
    pub fn frame(&mut self, chunks: Vec<Chunk>) -> Result<(), FormatError> {
        for (k, c) in chunks.iter().enumerate() {
            let bad = |allowed: &str| FormatError::Invalid {
                field: "GSD chunk name".into(),
                value: format!("{:?}", c.name),
                allowed: allowed.into(),
            };
            if c.name.is_empty() || c.name.contains('\0') {
                return Err(bad("a non-empty name without NUL"));
            }
            if chunks[..k].iter().any(|o| o.name == c.name) {
                return Err(bad("each name once per frame"));
            }
            if c.m == 0 || c.data.len() as u64 != c.n * c.m as u64 * c.kind.size() as u64 {
                return Err(bad("N × M elements of its type, M ≥ 1"));
            }
        }
        self.frames.push(chunks);
        Ok(())
    }

    /// Number of frames.
    pub fn frames(&self) -> usize {
        self.frames.len()
    }

    /// The whole file.
    pub fn to_bytes(&self) -> Result<Vec<u8>, FormatError> {
        // Name ids in order of first use.
        let mut names: Vec<&str> = Vec::new();
        for c in self.frames.iter().flatten() {
            if !names.contains(&c.name.as_str()) {
                names.push(&c.name);
            }
        }
        if names.len() > u16::MAX as usize {
            return Err(FormatError::Invalid {
                field: "GSD chunk names".into(),
                value: names.len().to_string(),
                allowed: format!("at most {}", u16::MAX),
            });
        }
        let id = |name: &str| names.iter().position(|n| *n == name).unwrap() as u16;

        let mut out = vec![0u8; HEADER_BYTES];
        // Index entries (frame, id, N, location, M, type), sorted as
        // version 2 readers search them.
        let mut index: Vec<(u64, u16, u64, u64, u32, u8)> = Vec::new();
        for (f, chunks) in self.frames.iter().enumerate() {
            let mut sorted: Vec<&Chunk> = chunks.iter().collect();
            sorted.sort_by_key(|c| id(&c.name));
            for c in sorted {
                index.push((
                    f as u64,
                    id(&c.name),
                    c.n,
                    out.len() as u64,
                    c.m,
                    c.kind.id(),
                ));
                out.extend_from_slice(&c.data);
            }
        }
        out.resize(out.len().next_multiple_of(8), 0);
        let index_location = out.len() as u64;
        for &(frame, id, n, location, m, kind) in &index {
            out.extend_from_slice(&frame.to_le_bytes());
            out.extend_from_slice(&n.to_le_bytes());
            out.extend_from_slice(&(location as i64).to_le_bytes());
            out.extend_from_slice(&m.to_le_bytes());
            out.extend_from_slice(&id.to_le_bytes());
            out.push(kind);
            out.push(0);
        }
        let namelist_location = out.len() as u64;
        let mut list: Vec<u8> = names
            .iter()
            .flat_map(|n| n.bytes().chain(std::iter::once(0)))
            .collect();
        // At least one NUL after the last name: an empty name ends the list.
        list.resize((list.len() + 1).next_multiple_of(NAME_UNIT), 0);
        let namelist_units = (list.len() / NAME_UNIT) as u64;
        out.extend_from_slice(&list);

        let mut header = Vec::with_capacity(HEADER_BYTES);
        header.extend_from_slice(&MAGIC.to_le_bytes());
        header.extend_from_slice(&index_location.to_le_bytes());
        header.extend_from_slice(&(index.len() as u64).to_le_bytes());
        header.extend_from_slice(&namelist_location.to_le_bytes());
        header.extend_from_slice(&namelist_units.to_le_bytes());
        let (major, minor) = self.schema_version;
        header.extend_from_slice(&((major as u32) << 16 | minor as u32).to_le_bytes());
        header.extend_from_slice(&VERSION.to_le_bytes());
        for text in [&self.application, &self.schema] {
            let mut field = [0u8; 64];
            let bytes = text.as_bytes();
            let n = bytes.len().min(63);
            field[..n].copy_from_slice(&bytes[..n]);
            header.extend_from_slice(&field);
        }
        header.resize(HEADER_BYTES, 0);
        out[..HEADER_BYTES].copy_from_slice(&header);
        Ok(out)
    }
}

/// A file read back by [`read`]: the header's names and versions and the
/// frames' chunks.
#[derive(Clone, Debug, PartialEq)]
pub struct File {
    /// The application that wrote it.
    pub application: String,
    /// The schema's name.
    pub schema: String,
    /// The schema's version, `(major, minor)`.
    pub schema_version: (u16, u16),
    /// The file layer's version, `major << 16 | minor`.
    pub version: u32,
    /// Every frame's chunks, in index order.
    pub frames: Vec<Vec<Chunk>>,
}

impl File {
    /// The chunk `name` of frame `frame`.
    pub fn chunk(&self, frame: usize, name: &str) -> Option<&Chunk> {
        self.frames.get(frame)?.iter().find(|c| c.name == name)
    }
}

/// Read a version 2 GSD file laid out as [`Writer`] writes it, checking
/// the header, that every chunk lies in the file and the index order.
pub fn read(bytes: &[u8]) -> Result<File, FormatError> {
    let corrupt = |what: &str| FormatError::Parse {
        file: "GSD".into(),
        message: what.to_string(),
    };
    let u64_at = |at: usize| -> Result<u64, FormatError> {
        bytes
            .get(at..at + 8)
            .map(|b| u64::from_le_bytes(b.try_into().unwrap()))
            .ok_or_else(|| corrupt("truncated"))
    };
    let u32_at = |at: usize| -> Result<u32, FormatError> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap()))
            .ok_or_else(|| corrupt("truncated"))
    };
    if u64_at(0)? != MAGIC {
        return Err(corrupt("not a GSD file (magic)"));
    }
    let index_location = u64_at(8)? as usize;
    let entries = u64_at(16)? as usize;
    let namelist_location = u64_at(24)? as usize;
    let namelist_bytes = u64_at(32)? as usize * NAME_UNIT;
    let schema_version = u32_at(40)?;
    let version = u32_at(44)?;
    if version >> 16 != 2 {
        return Err(corrupt("not a version 2 file"));
    }
    let text = |at: usize| {
        let field = &bytes[at..at + 64];
        let end = field.iter().position(|&b| b == 0).unwrap_or(64);
        String::from_utf8_lossy(&field[..end]).into_owned()
    };
    let list = bytes
        .get(namelist_location..namelist_location + namelist_bytes)
        .ok_or_else(|| corrupt("name list outside the file"))?;
    if list.last() != Some(&0) {
        return Err(corrupt("name list not NUL-terminated"));
    }
    let names: Vec<String> = list
        .split(|&b| b == 0)
        .take_while(|n| !n.is_empty())
        .map(|n| String::from_utf8_lossy(n).into_owned())
        .collect();
    let mut frames: Vec<Vec<Chunk>> = Vec::new();
    let mut last = (0u64, 0u16);
    for e in 0..entries {
        let at = index_location + e * INDEX_ENTRY_BYTES;
        let frame = u64_at(at)?;
        let n = u64_at(at + 8)?;
        let location = u64_at(at + 16)? as usize;
        let m = u32_at(at + 24)?;
        let id = u16::from_le_bytes(
            bytes
                .get(at + 28..at + 30)
                .ok_or_else(|| corrupt("truncated"))?
                .try_into()
                .unwrap(),
        );
        let (kind, flags) = (bytes[at + 30], bytes[at + 31]);
        let kind = Kind::from_id(kind).ok_or_else(|| corrupt("unknown chunk type"))?;
        if flags != 0 || m == 0 || location == 0 {
            return Err(corrupt("bad index entry"));
        }
        if e > 0 && (frame, id) <= last {
            return Err(corrupt("index not sorted by frame and name id"));
        }
        last = (frame, id);
        let size = n as usize * m as usize * kind.size();
        let data = bytes
            .get(location..location + size)
            .ok_or_else(|| corrupt("chunk outside the file"))?
            .to_vec();
        let name = names
            .get(id as usize)
            .ok_or_else(|| corrupt("name id outside the name list"))?
            .clone();
        while frames.len() <= frame as usize {
            frames.push(Vec::new());
        }
        frames[frame as usize].push(Chunk {
            name,
            kind,
            n,
            m,
            data,
        });
    }
    Ok(File {
        application: text(48),
        schema: text(112),
        schema_version: ((schema_version >> 16) as u16, schema_version as u16),
        version,
        frames,
    })
}

impl Chunk {
    /// The elements as `f64` (from `float32` or `float64`), `None` for
    /// other types.
    pub fn floats(&self) -> Option<Vec<f64>> {
        match self.kind {
            Kind::F32 => Some(
                self.data
                    .chunks_exact(4)
                    .map(|b| f32::from_le_bytes(b.try_into().unwrap()) as f64)
                    .collect(),
            ),
            Kind::F64 => Some(
                self.data
                    .chunks_exact(8)
                    .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
                    .collect(),
            ),
            _ => None,
        }
    }

    /// The elements as `u64` (from any unsigned type), `None` otherwise.
    pub fn unsigned(&self) -> Option<Vec<u64>> {
        let size = self.kind.size();
        match self.kind {
            Kind::U8 | Kind::U32 | Kind::U64 => Some(
                self.data
                    .chunks_exact(size)
                    .map(|b| {
                        let mut w = [0u8; 8];
                        w[..size].copy_from_slice(b);
                        u64::from_le_bytes(w)
                    })
                    .collect(),
            ),
            _ => None,
        }
    }

    /// The rows of an `int8` matrix as strings, each up to its first NUL.
    pub fn rows_as_strings(&self) -> Option<Vec<String>> {
        if self.kind != Kind::I8 {
            return None;
        }
        Some(
            self.data
                .chunks_exact(self.m as usize)
                .map(|row| {
                    let end = row.iter().position(|&b| b == 0).unwrap_or(row.len());
                    String::from_utf8_lossy(&row[..end]).into_owned()
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_frames() -> Writer {
        let mut w = Writer::new("jamkit test", "hoomd", (1, 4));
        w.frame(vec![
            Chunk::u32("particles/N", &[2]),
            Chunk::f32("particles/position", 3, &[0.1, 0.2, 0.3, -1.0, -2.0, 0.0]),
            Chunk::strings("particles/types", &["A".into(), "long".into()]),
        ])
        .unwrap();
        // A name first used in the second frame, listed before older ones.
        w.frame(vec![
            Chunk::u64("configuration/step", 7),
            Chunk::u32("particles/N", &[1]),
            Chunk::f64("log/value", 1, &[0.25]),
        ])
        .unwrap();
        w
    }

    /// The header's fields sit at the byte offsets of the GSD header
    /// struct, and the index and name list where the header says.
    #[test]
    fn header_index_and_names_at_their_offsets() {
        let bytes = two_frames().to_bytes().unwrap();
        let u64_at = |at: usize| u64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
        assert_eq!(u64_at(0), MAGIC);
        let index = u64_at(8) as usize;
        assert_eq!(u64_at(16), 6, "one index entry per chunk");
        let names = u64_at(24) as usize;
        assert_eq!(names, index + 6 * INDEX_ENTRY_BYTES);
        assert_eq!(index % 8, 0);
        let units = u64_at(32) as usize;
        assert_eq!(
            names + units * NAME_UNIT,
            bytes.len(),
            "name list ends the file"
        );
        assert_eq!(&bytes[40..44], &((1u32 << 16) | 4).to_le_bytes());
        assert_eq!(&bytes[44..48], &(2u32 << 16).to_le_bytes());
        assert_eq!(&bytes[48..60], b"jamkit test\0");
        assert_eq!(&bytes[112..118], b"hoomd\0");
        assert!(bytes[176..256].iter().all(|&b| b == 0));
        // The first chunk's data follows the header.
        let first = u64_at(index + 16);
        assert_eq!(first, HEADER_BYTES as u64);
        let list = &bytes[names..];
        assert!(list.starts_with(
            b"particles/N\0particles/position\0particles/types\0configuration/step\0log/value\0\0"
        ));
    }

    /// What is written reads back: names, shapes, types, values (float32
    /// to its rounding), frames, index sorted by (frame, name id).
    #[test]
    fn a_file_reads_back() {
        let bytes = two_frames().to_bytes().unwrap();
        let f = read(&bytes).unwrap();
        assert_eq!(
            (f.application.as_str(), f.schema.as_str()),
            ("jamkit test", "hoomd")
        );
        assert_eq!(f.schema_version, (1, 4));
        assert_eq!(f.frames.len(), 2);
        let pos = f.chunk(0, "particles/position").unwrap();
        assert_eq!((pos.n, pos.m, pos.kind), (2, 3, Kind::F32));
        let want = [0.1, 0.2, 0.3, -1.0, -2.0, 0.0];
        for (a, b) in pos.floats().unwrap().iter().zip(want) {
            assert_eq!(*a, b as f32 as f64);
        }
        let types = f.chunk(0, "particles/types").unwrap();
        assert_eq!((types.n, types.m), (2, 5));
        assert_eq!(types.rows_as_strings().unwrap(), ["A", "long"]);
        assert_eq!(
            f.chunk(1, "configuration/step")
                .unwrap()
                .unsigned()
                .unwrap(),
            [7]
        );
        assert_eq!(f.chunk(1, "particles/N").unwrap().unsigned().unwrap(), [1]);
        assert_eq!(f.chunk(1, "log/value").unwrap().floats().unwrap(), [0.25]);
        assert!(f.chunk(1, "particles/position").is_none());
        // Frame 1 lists particles/N (id 0) before configuration/step (id 3).
        let order: Vec<&str> = f.frames[1].iter().map(|c| c.name.as_str()).collect();
        assert_eq!(order, ["particles/N", "configuration/step", "log/value"]);
    }

    #[test]
    fn bad_chunks_are_refused_with_their_name() {
        let mut w = Writer::new("a", "b", (1, 0));
        let e = w
            .frame(vec![Chunk::u64("x", 1), Chunk::u64("x", 2)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("\"x\"") && e.contains("once per frame"), "{e}");
        let e = w.frame(vec![Chunk::u64("", 1)]).unwrap_err().to_string();
        assert!(e.contains("non-empty"), "{e}");
        assert_eq!(w.frames(), 0);
        let mut bytes = two_frames().to_bytes().unwrap();
        bytes[0] ^= 1;
        assert!(read(&bytes).unwrap_err().to_string().contains("magic"));
    }
}
