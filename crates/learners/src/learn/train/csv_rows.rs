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
