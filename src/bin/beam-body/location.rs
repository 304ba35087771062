//! Where in a file an error is: the compiler's `PATH:LINE:COLUMN: message`.

/// A file's error, "line 3: …" or "line 3, column 7: …", as "PATH:3: …" or "PATH:3:7: …".
pub fn at_file(path: &str, message: &str) -> String {
    let Some(rest) = message.strip_prefix("line ") else {
        return format!("{path}: {message}");
    };
    let digits = |s: &str| s.chars().take_while(char::is_ascii_digit).count();
    let n = digits(rest);
    let (line, rest) = rest.split_at(n);
    if let Some(rest) = rest.strip_prefix(", column ") {
        let m = digits(rest);
        let (column, rest) = rest.split_at(m);
        return format!("{path}:{line}:{column}{rest}");
    }
    format!("{path}:{line}{rest}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn file_errors_name_the_file_and_line() {
        assert_eq!(at_file("a.toml", "line 3: `x`: bad"), "a.toml:3: `x`: bad");
        assert_eq!(at_file("a.toml", "line 3, column 7: bad"), "a.toml:3:7: bad");
        assert_eq!(at_file("a.toml", "bad"), "a.toml: bad");
    }
}
