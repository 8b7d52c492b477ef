//! Float reference forward pass, for tests and the trainer's quantization checks only: the flight path
//! is integer. Same shapes as the integer layers.

/// A float dense layer: `y = W x + b`, optional ReLU.
pub struct FloatDense<const IN: usize, const OUT: usize> {
    pub weights: [[f32; IN]; OUT],
    pub bias: [f32; OUT],
    pub relu: bool,
}

impl<const IN: usize, const OUT: usize> FloatDense<IN, OUT> {
    pub fn forward(&self, x: &[f32; IN]) -> [f32; OUT] {
        let mut y = [0f32; OUT];
        for ((y, row), b) in y.iter_mut().zip(self.weights.iter()).zip(self.bias.iter()) {
            let s = row.iter().zip(x.iter()).fold(*b, |s, (w, x)| s + w * x);
            *y = if self.relu { s.max(0.0) } else { s };
        }
        y
    }
}
