//! XML helpers on quick-xml: attribute escaping for the writer, and a minimal element tree
//! for reading modelDescription.xml back (the parse-back test; compiled for the tests only).

#[cfg(test)]
use quick_xml::events::Event;
#[cfg(test)]
use quick_xml::Reader;

#[cfg(test)]
use crate::Result;

/// One element: its name, attributes in document order, and child elements. Text is not
/// kept; a modelDescription has none (the reader rejects any that is not whitespace).
#[cfg(test)]
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    pub name: String,
    pub attrs: Vec<(String, String)>,
    pub children: Vec<Element>,
}

#[cfg(test)]
impl Element {
    /// Parses a whole document and returns its root element.
    pub fn parse(text: &str) -> Result<Element> {
        let mut reader = Reader::from_str(text);
        reader.config_mut().trim_text(true);
        // Ancestors of the element being read; the root ends up alone at the bottom.
        let mut stack: Vec<Element> = Vec::new();
        let mut root = None;
        loop {
            let position = reader.buffer_position();
            let event = reader
                .read_event()
                .map_err(|err| format!("XML error near byte {position}: {err}"))?;
            match event {
                Event::Start(start) | Event::Empty(start) if root.is_some() => {
                    let name = String::from_utf8_lossy(start.name().as_ref()).into_owned();
                    return Err(format!("a second root element <{name}>").into());
                }
                Event::Start(start) => stack.push(Element::from_start(&start)?),
                Event::Empty(start) => {
                    let element = Element::from_start(&start)?;
                    match stack.last_mut() {
                        Some(parent) => parent.children.push(element),
                        None => root = Some(element),
                    }
                }
                Event::End(_) => {
                    // quick-xml checks that end names match their start.
                    let element = stack.pop().ok_or("an end tag without a start")?;
                    match stack.last_mut() {
                        Some(parent) => parent.children.push(element),
                        None => root = Some(element),
                    }
                }
                Event::Text(text) => {
                    let content = text.decode().map_err(|err| format!("bad text: {err}"))?;
                    if !content.trim().is_empty() {
                        return Err(format!("unexpected text {content:?}").into());
                    }
                }
                Event::Eof => break,
                // The declaration, comments, processing instructions.
                _ => {}
            }
        }
        if let Some(open) = stack.last() {
            return Err(format!("<{}> is not closed", open.name).into());
        }
        root.ok_or_else(|| "no root element".into())
    }

    fn from_start(start: &quick_xml::events::BytesStart) -> Result<Element> {
        let name = String::from_utf8_lossy(start.name().as_ref()).into_owned();
        let mut attrs = Vec::new();
        for attr in start.attributes() {
            let attr = attr.map_err(|err| format!("<{name}>: bad attribute: {err}"))?;
            let key = String::from_utf8_lossy(attr.key.as_ref()).into_owned();
            let value = attr
                .unescape_value()
                .map_err(|err| format!("<{name} {key}>: bad value: {err}"))?
                .into_owned();
            attrs.push((key, value));
        }
        Ok(Element { name, attrs, children: Vec::new() })
    }

    /// The value of attribute `key`, if present.
    pub fn attr(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// The value of attribute `key`, which must be present.
    pub fn required(&self, key: &str) -> Result<&str> {
        self.attr(key).ok_or_else(|| format!("<{}> has no attribute {key}", self.name).into())
    }

    /// The only child called `name`.
    pub fn child(&self, name: &str) -> Result<&Element> {
        let mut found = self.children.iter().filter(|c| c.name == name);
        match (found.next(), found.next()) {
            (Some(child), None) => Ok(child),
            (None, _) => Err(format!("<{}> has no <{name}>", self.name).into()),
            (Some(_), Some(_)) => Err(format!("<{}> has more than one <{name}>", self.name).into()),
        }
    }
}

/// `value` escaped for a double-quoted attribute: `&`, `<`, `>`, `"`, and the whitespace that
/// attribute normalisation would otherwise turn into spaces. Apostrophes stay readable
/// (quick-xml's `escape` would write `&apos;`).
pub fn escape_attr(value: &str) -> String {
    let mut out = String::with_capacity(value.len());
    for c in value.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\n' => out.push_str("&#10;"),
            '\r' => out.push_str("&#13;"),
            '\t' => out.push_str("&#9;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{escape_attr, Element};

    #[test]
    fn tree_and_escapes_round_trip() {
        let value = "a < b & \"c\" > d's\ttab";
        let text = format!(
            "<?xml version=\"1.0\"?>\n<root x=\"{}\">\n  <a/>\n  <b k=\"1\"><c/></b>\n</root>\n",
            escape_attr(value)
        );
        let root = Element::parse(&text).unwrap();
        assert_eq!(root.name, "root");
        assert_eq!(root.attr("x"), Some(value));
        assert_eq!(root.children.len(), 2);
        assert_eq!(root.child("b").unwrap().required("k").unwrap(), "1");
        assert_eq!(root.child("b").unwrap().children[0].name, "c");
        assert!(root.child("c").is_err());
        assert!(root.child("a").unwrap().required("k").is_err());
    }

    #[test]
    fn rejects_bad_documents() {
        assert!(Element::parse("<a><b></a>").is_err());
        assert!(Element::parse("<a>text</a>").is_err());
        assert!(Element::parse("<a/><b/>").is_err());
        assert!(Element::parse("<a x=\"1\" x=\"2\"/>").is_err());
        assert!(Element::parse("").is_err());
    }
}
