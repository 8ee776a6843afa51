//! The lexer and number parsing.

use super::*;

#[test]
fn lexer_locates_tokens_across_crlf_comments_and_continuations() {
    let src = "v 1 2 3\r\n# comment\r\n  f 1\t2 \\\r\n 3 # tail \\\nvt é 0\n\n";
    assert_eq!(
        lines(src),
        vec![
            vec![t("v", 1, 1), t("1", 1, 3), t("2", 1, 5), t("3", 1, 7)],
            vec![t("f", 3, 3), t("1", 3, 5), t("2", 3, 7), t("3", 4, 2)],
            vec![t("vt", 5, 1), t("é", 5, 4), t("0", 5, 6)],
        ]
    );
    // A backslash on the last line, and no final newline.
    assert_eq!(lines("f 1 \\"), vec![vec![t("f", 1, 1), t("1", 1, 3)]]);
    assert!(lines("").is_empty());
    assert!(lines("\n\r\n# x\n").is_empty());
}

#[test]
fn lexer_replaces_invalid_utf8() {
    let mut lexer = Lexer::new(b"o caf\xe9 bar\nv 0 0 0\n");
    let mut line = Line::default();
    assert!(lexer.next_line(&mut line));
    assert!(line.invalid_utf8);
    assert_eq!(line.tok(1), "caf\u{fffd}");
    assert_eq!(line.pos(2), Pos { line: 1, col: 8 });
    assert!(lexer.next_line(&mut line));
    assert!(!line.invalid_utf8);
}

#[test]
fn numbers() {
    assert_eq!(parse_f32("1.5"), Ok(1.5));
    assert_eq!(parse_f32("-2e-3"), Ok(-2e-3));
    assert_eq!(parse_f32("+.5"), Ok(0.5));
    assert_eq!(parse_f32("1e-50"), Ok(0.0));
    for bad in ["nan", "NaN", "inf", "-infinity"] {
        assert!(
            parse_f32(bad).unwrap_err().contains("not a finite number"),
            "{bad}"
        );
    }
    assert!(parse_f32("1e39").unwrap_err().contains("too large"));
    assert!(parse_f32("1,5").unwrap_err().contains("expected a number"));

    assert_eq!(resolve_index("1", "vertex", 3), Ok(0));
    assert_eq!(resolve_index("3", "vertex", 3), Ok(2));
    assert_eq!(resolve_index("-1", "vertex", 3), Ok(2));
    assert_eq!(resolve_index("-3", "vertex", 3), Ok(0));
    assert!(
        resolve_index("0", "vertex", 3)
            .unwrap_err()
            .contains("index 0")
    );
    assert!(
        resolve_index("4", "vertex", 3)
            .unwrap_err()
            .contains("out of range")
    );
    assert!(
        resolve_index("-4", "vertex", 3)
            .unwrap_err()
            .contains("out of range")
    );
    let huge = resolve_index("99999999999999999999999", "vertex", 3).unwrap_err();
    assert!(huge.contains("out of range"), "{huge}");
    assert!(
        resolve_index("x", "vertex", 3)
            .unwrap_err()
            .contains("expected")
    );
    assert!(
        resolve_index("-", "vertex", 3)
            .unwrap_err()
            .contains("expected")
    );
    assert!(
        resolve_index("", "normal", 3)
            .unwrap_err()
            .contains("missing normal")
    );
}
