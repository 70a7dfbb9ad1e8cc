//! What follows the last vertex: the elements the header declares after the vertices, then
//! nothing. Data after every declared element is refused, since a header whose vertex count is
//! below the file's rows would otherwise drop the rest of the Gaussians without a word.
use super::body::Body;
use super::header::Element;

/// Read past `after` (the elements declared after the vertices) and refuse anything left;
/// `declared` is every element of the header, for the message.
pub(super) fn check_end(
    body: &mut Body<'_>,
    after: &[Element],
    declared: &[Element],
) -> Result<(), String> {
    for element in after {
        body.skip(element)?;
    }
    let Some(left) = body.left_over() else { return Ok(()) };
    let elements: Vec<String> =
        declared.iter().map(|e| format!("element {} {}", e.name, e.count)).collect();
    Err(format!(
        "the file has {left} after the data the header declares ({}): a count below the file's \
         rows would drop the rest without a word; correct the header's counts",
        elements.join(", ")
    ))
}
