//! Reading the solver's CSV output and summarising a run.

use std::fs;
use std::path::Path;

use crate::{relative, Result};

/// A CSV file of numbers with a header line (`t,v1,theta1,u2,...`).
pub struct Table {
    columns: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    /// Reads `path`; empty lines and lines starting with `#` are skipped.
    pub fn read(path: &Path) -> Result<Table> {
        let name = relative(path);
        let text = fs::read_to_string(path).map_err(|err| format!("cannot read {name}: {err}"))?;
        Table::parse(&name, &text)
    }

    /// Parses the CSV `text` of the file `name` (for messages).
    fn parse(name: &str, text: &str) -> Result<Table> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, line)| (i + 1, line.trim()))
            .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'));

        let (_, header) = lines.next().ok_or_else(|| format!("{name} is empty"))?;
        // A header names its unit, `v1 [m]`; the columns go by name.
        let name_of = |c: &str| c.trim().split(" [").next().unwrap_or_default().to_owned();
        let columns: Vec<String> = header.split(',').map(name_of).collect();
        let mut rows = Vec::new();
        for (number, line) in lines {
            let row = line
                .split(',')
                .map(|field| field.trim().parse::<f64>())
                .collect::<Result<Vec<_>, _>>()
                .map_err(|err| format!("{name}:{number}: not a number ({err}): {line}"))?;
            if row.len() != columns.len() {
                return Err(format!(
                    "{name}:{number}: {} fields, but the header has {}",
                    row.len(),
                    columns.len()
                )
                .into());
            }
            rows.push(row);
        }
        if rows.is_empty() {
            return Err(format!("{name} has a header but no data").into());
        }
        Ok(Table { columns, rows })
    }

    /// The values of column `name`, in row order.
    pub fn values(&self, name: &str) -> Result<Vec<f64>> {
        let column = self.column(name)?;
        Ok(self.rows.iter().map(|row| row[column]).collect())
    }

    fn column(&self, name: &str) -> Result<usize> {
        self.columns.iter().position(|c| c == name).ok_or_else(|| {
            format!("no column `{name}` in the CSV (it has: {})", self.columns.join(", ")).into()
        })
    }

    /// The row at which `key(value of column)` is largest, ignoring NaN.
    fn argmax(&self, column: usize, key: impl Fn(f64) -> f64) -> &[f64] {
        self.rows
            .iter()
            .filter(|row| !row[column].is_nan())
            .max_by(|a, b| key(a[column]).total_cmp(&key(b[column])))
            .unwrap_or(&self.rows[0])
    }
}

/// Prints the summary of a run of the paper's scene.
pub fn print_paper_run(table: &Table) -> Result {
    let t = table.column("t")?;
    let v1 = table.column("v1")?;
    let theta1 = table.column("theta1")?;
    let u2 = table.column("u2")?;
    let last = &table.rows[table.rows.len() - 1];

    println!("rows          {}", table.rows.len());
    println!("t_end         {}", sig(last[t]));
    let row = table.argmax(v1, f64::abs);
    println!("max |v1|      {:<12}  at t = {}", sig(row[v1].abs()), sig(row[t]));
    let row = table.argmax(theta1, f64::abs);
    println!("max |theta1|  {:<12}  at t = {}", sig(row[theta1].abs()), sig(row[t]));
    let row = table.argmax(u2, |x| -x);
    println!("min u2        {:<12}  at t = {}", sig(row[u2]), sig(row[t]));
    println!("final values:");
    for (name, value) in table.columns.iter().zip(last) {
        println!("  {name:<11} {}", sig(*value));
    }
    let non_finite = table.rows.iter().flatten().filter(|x| !x.is_finite()).count();
    if non_finite > 0 {
        eprintln!("warning: {non_finite} values in the CSV are NaN or infinite");
    }
    Ok(())
}

/// `x` with six significant digits, like C's `%g`.
pub fn sig(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let exponent = x.abs().log10().floor();
    if (-4.0..6.0).contains(&exponent) {
        format!("{x:.*}", (5.0 - exponent) as usize)
    } else {
        format!("{x:.5e}")
    }
}

#[cfg(test)]
mod tests {
    use super::{sig, Table};

    #[test]
    fn parses_and_reports_bad_lines() {
        let table = Table::parse("a.csv", "# comment\nt [s], v1\n0, 1\n\n0.5, -2e-3\n").unwrap();
        assert_eq!(table.columns, ["t", "v1"]);
        assert_eq!(table.rows, [[0.0, 1.0], [0.5, -2e-3]]);

        let err = Table::parse("a.csv", "t,v1\n0,1\n1,x\n").err().unwrap();
        assert!(err.to_string().starts_with("a.csv:3: not a number"), "{err}");
        let err = Table::parse("a.csv", "t,v1\n0,1,2\n").err().unwrap();
        assert_eq!(err.to_string(), "a.csv:2: 3 fields, but the header has 2");
        assert!(Table::parse("a.csv", "t,v1\n").is_err());
    }

    #[test]
    fn six_significant_digits() {
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(10.0), "10.0000");
        assert_eq!(sig(-0.0839072), "-0.0839072");
        assert_eq!(sig(1.5e-7), "1.50000e-7");
    }
}
