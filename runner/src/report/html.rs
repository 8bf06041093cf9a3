//! The page's inline style sheet, and escaping text for it.

pub use crate::files::markup::escape;

/// Everything the page needs to look right, inline: no fonts, no scripts, nothing fetched.
pub const STYLE: &str = "\
body { font: 14px/1.45 system-ui, sans-serif; margin: 1.5em auto; max-width: 1400px; padding: 0 1em; color: #222; }
h1 { font-size: 1.5em; } h2 { border-top: 2px solid #ddd; padding-top: .8em; margin-top: 2em; }
code { background: #f3f3f3; padding: 0 .25em; border-radius: 3px; }
.meta { color: #555; }
nav a { margin-right: .8em; }
table { border-collapse: collapse; margin: .8em 0; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #ddd; padding: .2em .55em; text-align: right; }
th { background: #f6f6f6; } td:first-child, th:first-child { text-align: left; }
td:last-child:not(:first-child) { text-align: left; }
.regressed, .failed { background: #fde0dc; color: #a50e0e; font-weight: 600; }
.improved { background: #e0f4e4; color: #0d652d; }
.noisy, .insufficient { background: #fff4ce; }
.new, .missing { background: #e8f0fe; }
.verdict { padding: .5em .8em; border-radius: 4px; }
.verdict.good { background: #e0f4e4; } .verdict.bad { background: #fde0dc; }
.row { display: flex; flex-wrap: wrap; gap: .8em; align-items: flex-start; }
figure { margin: .4em 0; } figcaption { color: #555; font-size: .9em; }
.row img { max-width: 330px; height: auto; border: 1px solid #ccc; display: block; }
.crops img { max-width: none; display: inline-block; margin-right: .3em; vertical-align: top; }
img.zoom { image-rendering: pixelated; }
.plot svg { max-width: 100%; height: auto; border: 1px solid #eee; }
footer { color: #777; margin: 3em 0 1em; font-size: .9em; }
";
