//! The shared buffering and accounting loop of byte-stream decoders.

use crate::decoder::DecoderStats;

/// What a framer found at the start of the buffered bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Step {
    /// A frame may start here but is not complete yet.
    NeedMore,
    /// These bytes are not the start of a frame (garbage between frames).
    Skip(usize),
    /// A frame started here but failed a check; drop this many bytes and look again.
    Bad(usize),
    /// A valid frame of this length was consumed.
    Frame(usize),
}

/// Buffer of bytes not yet consumed, plus the decoder's counts.
#[derive(Clone, Debug, Default)]
pub(crate) struct ByteStream {
    buffer: Vec<u8>,
    pub(crate) stats: DecoderStats,
}

impl ByteStream {
    pub(crate) fn pending(&self) -> usize {
        self.buffer.len()
    }

    pub(crate) fn reset(&mut self) {
        self.buffer.clear();
        self.stats = DecoderStats::default();
    }

    /// Appends `bytes` and runs `next_step` on the unconsumed bytes until it needs more.
    /// `next_step` must only look at the slice it is given; a step that claims zero bytes or
    /// more than it was given is clamped, so a faulty framer can never loop or panic.
    pub(crate) fn push(&mut self, bytes: &[u8], mut next_step: impl FnMut(&[u8]) -> Step) {
        self.stats.bytes_received += bytes.len() as u64;
        self.buffer.extend_from_slice(bytes);
        let mut consumed = 0usize;
        while let Some(window) = self.buffer.get(consumed..) {
            if window.is_empty() {
                break;
            }
            let step = next_step(window);
            let clamp = |n: usize| n.clamp(1, window.len());
            match step {
                Step::NeedMore => break,
                Step::Skip(n) => {
                    let n = clamp(n);
                    self.stats.skipped_bytes += n as u64;
                    consumed += n;
                }
                Step::Bad(n) => {
                    let n = clamp(n);
                    self.stats.bad_frames += 1;
                    self.stats.skipped_bytes += n as u64;
                    consumed += n;
                }
                Step::Frame(n) => {
                    let n = clamp(n);
                    self.stats.frames += 1;
                    self.stats.bytes_in_frames += n as u64;
                    consumed += n;
                }
            }
        }
        self.buffer.drain(..consumed.min(self.buffer.len()));
    }

    /// Takes the unconsumed bytes out (for `finish`), without counting them.
    pub(crate) fn take_pending(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.buffer)
    }

    /// Counts a truncated tail as skipped and clears it.
    pub(crate) fn drop_pending(&mut self) {
        self.stats.skipped_bytes += self.buffer.len() as u64;
        self.buffer.clear();
    }
}

impl ByteStream {
    /// End of a line-based stream: the unterminated tail is parsed as one more line.
    pub(crate) fn finish_line(
        &mut self,
        samples: &mut Vec<crate::decoder::Sample>,
        parse: impl FnOnce(&[u8]) -> Option<crate::decoder::Sample>,
    ) {
        let tail = self.take_pending();
        if tail.is_empty() {
            return;
        }
        let line = tail.strip_suffix(b"\r").unwrap_or(&tail);
        if line.iter().all(u8::is_ascii_whitespace) {
            self.stats.skipped_bytes += tail.len() as u64;
            return;
        }
        match parse(line) {
            Some(sample) => {
                samples.push(sample);
                self.stats.samples += 1;
                self.stats.frames += 1;
                self.stats.bytes_in_frames += tail.len() as u64;
            }
            None => {
                self.stats.bad_frames += 1;
                self.stats.skipped_bytes += tail.len() as u64;
            }
        }
    }
}
