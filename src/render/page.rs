//! The HTML of a report: a page of sections holding paragraphs, tables and figures. The page is
//! well-formed XML as well as HTML (every element closed, text escaped), so that a test can read
//! it with an XML parser.

/// Escapes text for HTML (element content and quoted attribute values).
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('\'', "&#39;")
        .replace('"', "&quot;")
}

/// A number for tables: `0`, or two significant digits in scientific notation (`1.5e-13`).
pub fn sci(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else {
        format!("{x:.1e}")
    }
}

/// A table as HTML: header cells and rows of already formatted cells.
pub fn table(header: &[&str], rows: &[Vec<String>]) -> String {
    table_with_id("", header, rows)
}

/// [`table`] with an `id` (none when empty), so readers and tests can find it.
pub fn table_with_id(id: &str, header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = if id.is_empty() {
        String::from("<table><tr>")
    } else {
        format!("<table id='{}'><tr>", escape(id))
    };
    for h in header {
        s += &format!("<th>{}</th>", escape(h));
    }
    s += "</tr>";
    for r in rows {
        s += "<tr>";
        for c in r {
            s += &format!("<td>{}</td>", escape(c));
        }
        s += "</tr>";
    }
    s + "</table>"
}

/// A paragraph of plain text.
pub fn para(text: &str) -> String {
    format!("<p>{}</p>", escape(text))
}

/// A list of plain-text items.
pub fn list(items: &[String]) -> String {
    let li: String = items
        .iter()
        .map(|i| format!("<li>{}</li>", escape(i)))
        .collect();
    format!("<ul>{li}</ul>")
}

/// A figure: the image `file` (beside the page) and its caption.
pub fn figure(file: &str, caption: &str) -> String {
    format!(
        "<figure><a href='{f}'><img src='{f}' alt='{c}'/></a><figcaption>{c}</figcaption></figure>",
        f = escape(file),
        c = escape(caption)
    )
}

/// A section of a page: its anchor, heading and HTML body.
#[derive(Debug, Clone, PartialEq)]
pub struct Section {
    pub id: String,
    pub heading: String,
    pub body: String,
}

impl Section {
    pub fn new(id: impl Into<String>, heading: impl Into<String>, body: String) -> Self {
        Self {
            id: id.into(),
            heading: heading.into(),
            body,
        }
    }
}

const STYLE: &str = "body{font-family:sans-serif;max-width:1200px;margin:2em auto;padding:0 1em;\
     line-height:1.4}table{border-collapse:collapse;margin:1em 0}\
     td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}\
     td:first-child,th:first-child{text-align:left}th{background:#f4f4f4}\
     img{max-width:100%;border:0}figure{margin:1.5em 0}figcaption{color:#333;font-size:95%}";

/// The page: a title, an introduction (HTML), a table of contents, then the sections.
pub fn document(title: &str, intro: &str, sections: &[Section]) -> String {
    let mut s = format!(
        "<!DOCTYPE html>\n<html lang='en'><head><meta charset='utf-8'/><title>{t}</title>\
         <style>{STYLE}</style></head><body><h1>{t}</h1>{intro}",
        t = escape(title)
    );
    if sections.len() > 2 {
        s += "<nav><ol>";
        for sec in sections {
            s += &format!(
                "<li><a href='#{}'>{}</a></li>",
                escape(&sec.id),
                escape(&sec.heading)
            );
        }
        s += "</ol></nav>";
    }
    for sec in sections {
        s += &format!(
            "<section id='{}'><h2>{}</h2>{}</section>",
            escape(&sec.id),
            escape(&sec.heading),
            sec.body
        );
    }
    s + "</body></html>\n"
}

/// A page of (heading, HTML body) sections without introduction.
pub fn page(title: &str, sections: &[(String, String)]) -> String {
    let sections: Vec<Section> = sections
        .iter()
        .enumerate()
        .map(|(i, (h, b))| Section::new(format!("s{}", i + 1), h.clone(), b.clone()))
        .collect();
    document(title, "", &sections)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tables_and_pages_escape_their_text() {
        let t = table(&["a", "b"], &[vec!["1".into(), "<2>".into()]]);
        assert_eq!(
            t,
            "<table><tr><th>a</th><th>b</th></tr><tr><td>1</td><td>&lt;2&gt;</td></tr></table>"
        );
        let p = page("x & y", &[("h".into(), para("T < 1 s"))]);
        assert!(p.contains("<title>x &amp; y</title>") && p.contains("<p>T &lt; 1 s</p>"));
        assert!(figure("a.svg", "it's").contains("alt='it&#39;s'"));
    }
}
