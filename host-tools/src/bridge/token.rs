//! The pairing token: the secret a client's first line must carry when the bridge has one.

use rand::Rng;
use serde::Deserialize;

/// Bytes of randomness in a token the bridge makes (written as twice as many hex digits).
const RANDOM_BYTES: usize = 16;
/// Longest token `--token` takes, bytes.
const MAX_TOKEN: usize = 256;

/// A pairing token. Its `Debug` does not show it.
#[derive(Clone, PartialEq, Eq)]
pub struct PairingToken(String);

impl std::fmt::Debug for PairingToken {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PairingToken(..)")
    }
}

/// A client's first line where a token is needed: `{"token": "..."}` and nothing else.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TokenLine {
    token: String,
}

impl PairingToken {
    /// `given` as a token: 1 to 256 bytes, no control characters.
    ///
    /// # Errors
    /// Saying which rule `given` breaks.
    pub fn parse(given: &str) -> Result<PairingToken, String> {
        if given.is_empty() || given.len() > MAX_TOKEN {
            return Err(format!(
                "a pairing token has 1 to {MAX_TOKEN} bytes, not {}",
                given.len()
            ));
        }
        if given.chars().any(char::is_control) {
            return Err("a pairing token has no control characters".into());
        }
        Ok(PairingToken(given.to_string()))
    }

    /// A fresh token: 16 bytes from the operating system's generator (through
    /// `rand`'s thread generator, which it seeds), as lowercase hex.
    pub fn generate() -> PairingToken {
        let bytes: [u8; RANDOM_BYTES] = rand::rng().random();
        PairingToken(bytes.iter().map(|b| format!("{b:02x}")).collect())
    }

    /// The token, to print for the operator.
    pub fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `line` is `{"token": T}` with this token (compared in time independent of where
    /// it differs).
    pub fn opens(&self, line: &[u8]) -> bool {
        let Ok(TokenLine { token }) = serde_json::from_slice(line) else {
            return false;
        };
        let (given, mine) = (token.as_bytes(), self.0.as_bytes());
        given.len() == mine.len() && given.iter().zip(mine).fold(0, |d, (a, b)| d | (a ^ b)) == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_exact_token_line_opens() {
        let token = PairingToken::parse("s3cret").unwrap();
        assert!(token.opens(br#"{"token": "s3cret"}"#));
        assert!(token.opens(br#" {"token":"s3cret"} "#));
        for wrong in [
            &br#"{"token": "s3cre"}"#[..],
            br#"{"token": "s3cret2"}"#,
            br#"{"token": "s3cret", "more": 1}"#,
            br#"{"Token": "s3cret"}"#,
            br#""s3cret""#,
            b"s3cret",
            b"",
        ] {
            assert!(!token.opens(wrong), "{}", String::from_utf8_lossy(wrong));
        }
    }

    #[test]
    fn generated_tokens_differ_and_are_hex() {
        let (a, b) = (PairingToken::generate(), PairingToken::generate());
        assert_ne!(a, b);
        assert_eq!(a.as_str().len(), 2 * RANDOM_BYTES);
        assert!(a.as_str().bytes().all(|c| c.is_ascii_hexdigit()));
        assert!(a.opens(format!(r#"{{"token": "{}"}}"#, a.as_str()).as_bytes()));
    }

    #[test]
    fn a_given_token_is_checked() {
        assert!(PairingToken::parse("").is_err());
        assert!(PairingToken::parse(&"t".repeat(MAX_TOKEN + 1)).is_err());
        assert!(PairingToken::parse("tab\there").is_err());
        assert!(PairingToken::parse(&"t".repeat(MAX_TOKEN)).is_ok());
        assert_eq!(
            format!("{:?}", PairingToken::parse("x").unwrap()),
            "PairingToken(..)"
        );
    }
}
