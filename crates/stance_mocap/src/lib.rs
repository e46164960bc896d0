//! Motion-capture sensors: streaming decoders, fusion and calibration.
