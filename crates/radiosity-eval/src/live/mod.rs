//! Watching a comparison as it runs: the scene and every solver's radiosity in a page in the
//! browser, live over HTTP on `127.0.0.1` or kept as one self-contained file.
//!
//! - [`LiveScene`] is what is sent once: geometry, the rule of smooth shading as a table
//!   ([`crate::CornerTable`]), the reference for the error map, the start camera, each
//!   solver's colour and dash as the PNG plots draw it ([`crate::style_of`]).
//! - [`Feed`] is what changes: each run's points (thinned, so a long run sends hundreds, not
//!   millions) and its radiosity at chosen moments, as `f32`. [`FeedWatch`] fills it from
//!   [`crate::Lab::compare_watched`]; it copies a state at most every [`FRAME_INTERVAL`]
//!   seconds for the live views, and at steps spaced by a factor [`KEPT_FACTOR`] for the kept
//!   page's slider, so watching costs the solvers a copy of `B` a few times a second.
//! - [`Server`] serves the page, the geometry and the feed as server-sent events; a client
//!   that is slow or leaves never holds the run up: each client's thread reads the feed under
//!   its lock and writes outside it, and skips to the latest radiosity.
//! - [`write_page`] writes the same page with the geometry and every kept moment inside it,
//!   and a slider over the run, for a paper's supplement or an issue.
//!
//! The page itself (`page.html`) is hand-written WebGL2 and plain JavaScript: no library, no
//! build step, nothing fetched from elsewhere, so it works offline and reads as one file.
//! It draws each patch with the radiosity at its corners interpolated as [`crate::render`]
//! does (barycentric on triangles, bilinear on quads), exposed by the exposure [`crate::render`]
//! would choose at the start camera ([`crate::ExposureProbe`], computed here for every
//! moment sent) and encoded with the sRGB curve; the error map colours each patch by
//! `|B − B*|` over the reference's area-weighted RMS (so that its area-weighted RMS is e_rms),
//! on a log scale.

pub(crate) mod feed;
pub(crate) mod page;
pub(crate) mod scene_view;
pub(crate) mod server;
