//! The framing every byte-stream decoder shares: a buffer of unconsumed bytes, the
//! [`DecoderStats`] bookkeeping and the loop that asks a protocol where its next frame is.
//!
//! A protocol only says what it sees at the start of the unconsumed bytes ([`FrameFormat`]
//! returning a [`Step`]); [`FramedDecoder`] does the rest: buffering across chunks, counting
//! frames, bad frames and skipped garbage, the end of the stream, resets. The counts keep
//! `bytes_received == bytes_in_frames + skipped_bytes + pending_bytes()` at all times.

use crate::decoder::{Decoder, DecoderStats, Protocol, Sample};

/// What a protocol found at the start of the unconsumed bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Step {
    /// A frame may start here but is not complete yet.
    NeedMore,
    /// These bytes are not the start of a frame (garbage between frames).
    Skip(usize),
    /// A frame started here but failed a check; drop this many bytes and look again.
    Bad(usize),
    /// A valid frame of this length was consumed.
    Frame(usize),
}

/// What one byte-stream protocol knows about its own frames.
pub trait FrameFormat {
    /// The protocol these frames belong to.
    const PROTOCOL: Protocol;
    /// Frames are text lines: at the end of the stream an unterminated last line is still
    /// parsed with [`FrameFormat::parse_last_line`] instead of being dropped.
    const LINE_BASED: bool = false;

    /// Looks at the start of the unconsumed bytes (`window`, never empty) and says what is
    /// there, appending the sample of a valid frame to `samples`. It must only look at
    /// `window`; a step claiming zero bytes or more than `window` holds is clamped.
    fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step;

    /// Parses the unterminated last line (without its CR) of a line-based protocol.
    fn parse_last_line(&self, line: &[u8]) -> Option<Sample> {
        let _ = line;
        None
    }
}

/// Buffer of bytes not yet consumed, plus the decoder's counts.
#[derive(Clone, Debug, Default)]
pub(crate) struct Framer {
    buffer: Vec<u8>,
    pub(crate) stats: DecoderStats,
}

impl Framer {
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

    /// Counts a truncated tail as skipped and clears it.
    pub(crate) fn drop_pending(&mut self) {
        self.stats.skipped_bytes += self.buffer.len() as u64;
        self.buffer.clear();
    }

    /// End of a line-based stream: the unterminated tail is parsed as one more line.
    pub(crate) fn finish_line(
        &mut self,
        samples: &mut Vec<Sample>,
        parse: impl FnOnce(&[u8]) -> Option<Sample>,
    ) {
        let tail = std::mem::take(&mut self.buffer);
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

/// A streaming [`Decoder`] made of a protocol's [`FrameFormat`] and the shared framing.
#[derive(Clone, Debug, Default)]
pub struct FramedDecoder<F> {
    format: F,
    framer: Framer,
}

impl<F> FramedDecoder<F> {
    /// A decoder reading frames of `format`, with empty buffer and counts.
    pub fn with_format(format: F) -> Self {
        FramedDecoder {
            format,
            framer: Framer::default(),
        }
    }

    /// The frame format (the protocol's configuration).
    pub fn format(&self) -> &F {
        &self.format
    }
}

impl<F: FrameFormat> Decoder for FramedDecoder<F> {
    fn protocol(&self) -> Protocol {
        F::PROTOCOL
    }

    fn push(&mut self, bytes: &[u8], samples: &mut Vec<Sample>) {
        let before = samples.len();
        let format = &self.format;
        self.framer
            .push(bytes, |window| format.next_frame(window, samples));
        self.framer.stats.samples += samples.len().saturating_sub(before) as u64;
    }

    fn finish(&mut self, samples: &mut Vec<Sample>) {
        if F::LINE_BASED {
            let format = &self.format;
            self.framer
                .finish_line(samples, |line| format.parse_last_line(line));
        } else {
            self.framer.drop_pending();
        }
    }

    fn stats(&self) -> DecoderStats {
        self.framer.stats
    }

    fn pending_bytes(&self) -> usize {
        self.framer.pending()
    }

    fn reset(&mut self) {
        self.framer.reset();
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;
    use crate::decoder::SensorId;

    /// Toy binary frames `'<' id '>'`; `'<' x '!'` is a bad frame.
    struct Angle;

    impl FrameFormat for Angle {
        const PROTOCOL: Protocol = Protocol::Xsens;

        fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
            match window {
                [b'<', id, b'>', ..] => {
                    samples.push(Sample {
                        sensor: SensorId(u16::from(*id)),
                        ..Sample::default()
                    });
                    Step::Frame(3)
                }
                [b'<', _, b'!', ..] => Step::Bad(3),
                [b'<'] | [b'<', _] => Step::NeedMore,
                // A faulty framer: claims nothing, then far too much.
                [b'0', ..] => Step::Skip(0),
                [b'9', ..] => Step::Frame(usize::MAX),
                _ => Step::Skip(1),
            }
        }
    }

    /// Toy text lines: a line is a sensor id.
    struct Lines;

    impl FrameFormat for Lines {
        const PROTOCOL: Protocol = Protocol::AsciiQuaternion;
        const LINE_BASED: bool = true;

        fn next_frame(&self, window: &[u8], samples: &mut Vec<Sample>) -> Step {
            let Some(newline) = window.iter().position(|&b| b == b'\n') else {
                return Step::NeedMore;
            };
            match self.parse_last_line(window.get(..newline).unwrap_or_default()) {
                Some(sample) => {
                    samples.push(sample);
                    Step::Frame(newline + 1)
                }
                None => Step::Bad(newline + 1),
            }
        }

        fn parse_last_line(&self, line: &[u8]) -> Option<Sample> {
            let id = std::str::from_utf8(line).ok()?.trim().parse().ok()?;
            Some(Sample {
                sensor: SensorId(id),
                ..Sample::default()
            })
        }
    }

    fn invariant_holds<F: FrameFormat>(decoder: &FramedDecoder<F>) -> bool {
        let stats = decoder.stats();
        stats.bytes_received
            == stats.bytes_in_frames + stats.skipped_bytes + decoder.pending_bytes() as u64
    }

    #[test]
    fn frames_split_across_chunks_garbage_and_bad_frames_are_counted() {
        let stream = b"xx<\x01><\x02!yy<\x03><\x04";
        let mut decoder = FramedDecoder::with_format(Angle);
        let mut samples = Vec::new();
        for byte in stream {
            decoder.push(std::slice::from_ref(byte), &mut samples);
            assert!(invariant_holds(&decoder));
        }
        let ids: Vec<u16> = samples.iter().map(|s| s.sensor.0).collect();
        assert_eq!(ids, [1, 3]);
        let stats = decoder.stats();
        assert_eq!(stats.frames, 2);
        assert_eq!(stats.samples, 2);
        assert_eq!(stats.bad_frames, 1);
        assert_eq!(stats.bytes_in_frames, 6);
        assert_eq!(stats.skipped_bytes, 7);
        assert_eq!(decoder.pending_bytes(), 2);
        decoder.finish(&mut samples);
        assert_eq!(samples.len(), 2, "a binary tail is dropped");
        assert_eq!(decoder.pending_bytes(), 0);
        assert_eq!(decoder.stats().skipped_bytes, 9);
        assert!(invariant_holds(&decoder));
        assert_eq!(decoder.protocol(), Protocol::Xsens);
        decoder.reset();
        assert_eq!(decoder.stats(), DecoderStats::default());
    }

    #[test]
    fn faulty_steps_are_clamped() {
        let mut decoder = FramedDecoder::with_format(Angle);
        let samples = decoder.decode(b"00<\x05>9ab");
        assert_eq!(samples.len(), 1);
        let stats = decoder.stats();
        assert_eq!(stats.skipped_bytes, 2, "Skip(0) still moves one byte");
        assert_eq!(
            stats.bytes_in_frames,
            3 + 3,
            "Frame(MAX) takes what there is"
        );
        assert_eq!(decoder.pending_bytes(), 0);
        assert!(invariant_holds(&decoder));
    }

    #[test]
    fn a_line_format_parses_its_unterminated_last_line() {
        let mut decoder = FramedDecoder::with_format(Lines);
        let mut samples = decoder.decode(b"1\nnope\n2\r\n3\r");
        assert_eq!(samples.len(), 2);
        assert_eq!(decoder.stats().bad_frames, 1);
        decoder.finish(&mut samples);
        let ids: Vec<u16> = samples.iter().map(|s| s.sensor.0).collect();
        assert_eq!(ids, [1, 2, 3]);
        assert_eq!(decoder.stats().samples, 3);
        assert_eq!(decoder.stats().frames, 3);
        assert!(invariant_holds(&decoder));
        let mut other = FramedDecoder::with_format(Lines);
        let mut none = other.decode(b"1\n  ");
        other.finish(&mut none);
        assert_eq!(other.stats().skipped_bytes, 2, "a blank tail is skipped");
        assert!(invariant_holds(&other));
    }
}
