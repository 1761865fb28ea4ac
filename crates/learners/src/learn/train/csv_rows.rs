//! The CSV files this program writes and reads back (training metrics,
//! periodic evaluations).

/// The rows of a CSV file this program wrote (none if it does not exist
/// yet); a malformed row is an error naming the file.
pub fn read_csv<T: serde::de::DeserializeOwned>(
    path: &std::path::Path,
) -> Result<Vec<T>, crate::error::LearnError> {
    use crate::error::LearnError;
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut r = csv::Reader::from_path(path).map_err(|cause| LearnError::Csv {
        context: format!("cannot read {}", path.display()),
        cause,
    })?;
    r.deserialize()
        .collect::<Result<Vec<T>, _>>()
        .map_err(|cause| LearnError::Csv {
            context: format!("{}: malformed row", path.display()),
            cause,
        })
}

/// Appends `row` to the CSV file at `path`, with a header when the file is
/// new.
pub fn append_row<T: serde::Serialize>(
    path: &std::path::Path,
    row: &T,
) -> Result<(), crate::error::LearnError> {
    use crate::error::LearnError;
    let fresh = !path.exists();
    let context = || format!("cannot write {}", path.display());
    let file = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .map_err(|e| LearnError::io(context(), e))?;
    let mut w = csv::WriterBuilder::new()
        .has_headers(fresh)
        .from_writer(file);
    w.serialize(row).map_err(|cause| LearnError::Csv {
        context: context(),
        cause,
    })?;
    w.flush().map_err(|e| LearnError::io(context(), e))?;
    Ok(())
}

/// Keeps the rows of the CSV file at `path` that `keep` accepts: on
/// resume, the rows of iterations past the last checkpoint go, since the
/// resumed run plays them again. The file is replaced in one atomic write,
/// so a kill in the middle leaves the old rows or the kept ones.
pub fn keep_rows<T: serde::Serialize + serde::de::DeserializeOwned>(
    path: &std::path::Path,
    keep: impl Fn(&T) -> bool,
) -> Result<(), crate::error::LearnError> {
    use crate::error::LearnError;
    if !path.exists() {
        return Ok(());
    }
    let context = || format!("cannot write {}", path.display());
    let mut w = csv::WriterBuilder::new().from_writer(Vec::new());
    for row in read_csv::<T>(path)?.iter().filter(|r| keep(r)) {
        w.serialize(row).map_err(|cause| LearnError::Csv {
            context: context(),
            cause,
        })?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| LearnError::io(context(), e.into_error()))?;
    if bytes.is_empty() {
        // No row kept: no file, so that the next row brings its header.
        std::fs::remove_file(path).map_err(|e| LearnError::io(context(), e))?;
    } else {
        t2e_core::fs::write_file_atomically(path, &bytes)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, PartialEq, serde::Serialize, serde::Deserialize)]
    struct Row {
        iteration: u64,
        share: f64,
    }

    #[test]
    fn rows_past_the_resume_point_are_dropped_and_the_rest_kept() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rows.csv");
        for iteration in 1..=4 {
            let share = iteration as f64 / 8.0;
            append_row(&path, &Row { iteration, share }).unwrap();
        }
        keep_rows(&path, |r: &Row| r.iteration <= 2).unwrap();
        append_row(
            &path,
            &Row {
                iteration: 3,
                share: 1.0,
            },
        )
        .unwrap();
        let rows: Vec<Row> = read_csv(&path).unwrap();
        let got: Vec<(u64, f64)> = rows.iter().map(|r| (r.iteration, r.share)).collect();
        assert_eq!(got, [(1, 0.125), (2, 0.25), (3, 1.0)]);
        assert_eq!(
            std::fs::read_to_string(&path)
                .unwrap()
                .matches("iteration")
                .count(),
            1
        );

        // Nothing kept: the next row starts the file again, header first.
        keep_rows(&path, |_: &Row| false).unwrap();
        append_row(
            &path,
            &Row {
                iteration: 1,
                share: 0.5,
            },
        )
        .unwrap();
        let rows: Vec<Row> = read_csv(&path).unwrap();
        assert_eq!(
            rows,
            [Row {
                iteration: 1,
                share: 0.5
            }]
        );
    }
}
