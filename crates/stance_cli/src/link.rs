//! `stance link encode DOC.json` / `stance link decode FRAGMENT_OR_URL`: the posture-link codec
//! of the editor (`stance_document::link`) from the command line. DOC.json is the editor's
//! document format (`docs/document-format.md`).

use std::io::Read;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow};
use stance_document::{Document, link};

#[derive(clap::Args, Debug)]
pub struct LinkArgs {
    #[command(subcommand)]
    pub command: LinkCommand,
}

#[derive(clap::Subcommand, Debug)]
pub enum LinkCommand {
    /// Print the URL fragment (the part after `#`) that carries a document.
    Encode {
        /// The document (JSON); `-` reads standard input.
        document: PathBuf,
    },
    /// Print the document (JSON) that a link carries; fails with the reason if it is damaged.
    Decode {
        /// The fragment, `#fragment`, or a whole URL containing `#`.
        link: String,
        /// One line instead of pretty-printed JSON.
        #[arg(long)]
        compact: bool,
    },
}

pub fn run(args: LinkArgs) -> Result<()> {
    match args.command {
        LinkCommand::Encode { document } => {
            let text = if document.as_os_str() == "-" {
                let mut s = String::new();
                std::io::stdin()
                    .read_to_string(&mut s)
                    .context("cannot read standard input")?;
                s
            } else {
                std::fs::read_to_string(&document)
                    .with_context(|| format!("cannot read {}", document.display()))?
            };
            let doc = Document::from_json(&text)
                .map_err(|e| anyhow!("invalid document {}: {e}", document.display()))?;
            println!("{}", link::encode(&doc));
            Ok(())
        }
        LinkCommand::Decode {
            link: text,
            compact,
        } => {
            let doc = link::decode(&text).map_err(|e| anyhow!("cannot open the link: {e}"))?;
            println!("{}", doc.to_json(!compact));
            Ok(())
        }
    }
}
