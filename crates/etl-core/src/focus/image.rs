//! A borrowed grayscale image with a row stride, 8- or 16-bit, for the sharpness measures.
//!
//! The view never copies: a camera driver's frame buffer (possibly with padding at the end
//! of each row, or a region of interest inside a larger frame) is measured in place.

use crate::error::{count_in_range, Error, Result};

/// Largest accepted width or height, px. It keeps every per-row sum of the measures in
/// `u64` without overflow (a row of 2^20 16-bit Sobel energies is below 2^64).
pub const MAX_SIDE_PX: usize = 1 << 20;

/// A grey level of 8 or 16 bits.
pub trait Pixel: Copy + private::Sealed {
    /// The grey level as an integer.
    fn level(self) -> i64;
}

impl Pixel for u8 {
    #[inline(always)]
    fn level(self) -> i64 {
        self as i64
    }
}

impl Pixel for u16 {
    #[inline(always)]
    fn level(self) -> i64 {
        self as i64
    }
}

mod private {
    pub trait Sealed {}
    impl Sealed for u8 {}
    impl Sealed for u16 {}
}

/// A read-only grayscale image: `height` rows of `width` pixels, row `y` starting at
/// `data[y * stride]`.
#[derive(Debug, Clone, Copy)]
pub struct ImageView<'a, T: Pixel> {
    data: &'a [T],
    width: usize,
    height: usize,
    stride: usize,
}

impl<'a, T: Pixel> ImageView<'a, T> {
    /// A view of `data` as `height` rows of `width` pixels spaced `stride` elements apart.
    ///
    /// Preconditions: `1 <= width <= stride`, `1 <= height`, both at most
    /// [`MAX_SIDE_PX`], and `data` holds at least `(height - 1) * stride + width` elements
    /// (the last row need not be padded).
    ///
    /// Errors: a zero or too large side ([`Error::OutOfRange`]), `stride < width`
    /// ([`Error::InvalidArgument`]), `data` too short ([`Error::BufferTooSmall`]).
    ///
    /// ```
    /// use etl_core::focus::ImageView;
    /// let frame = [0u8, 10, 20, 99, 30, 40, 50, 99]; // 3 px rows padded to 4
    /// let view = ImageView::new(&frame, 3, 2, 4).unwrap();
    /// assert_eq!(view.row(1), &[30, 40, 50]);
    /// ```
    pub fn new(data: &'a [T], width: usize, height: usize, stride: usize) -> Result<Self> {
        count_in_range(width, 1, MAX_SIDE_PX, "image width_px")?;
        count_in_range(height, 1, MAX_SIDE_PX, "image height_px")?;
        if stride < width {
            return Err(Error::InvalidArgument { what: "image stride is smaller than its width" });
        }
        // Both factors are at most 2^20 and stride is bounded by data.len() below, so a
        // product that overflows means the buffer is too small anyway.
        let needed = (height - 1)
            .checked_mul(stride)
            .and_then(|n| n.checked_add(width))
            .ok_or(Error::BufferTooSmall { what: "image data", needed: usize::MAX, got: data.len() })?;
        if data.len() < needed {
            return Err(Error::BufferTooSmall { what: "image data", needed, got: data.len() });
        }
        Ok(Self { data, width, height, stride })
    }

    /// A view of a tightly packed image (`stride == width`).
    pub fn packed(data: &'a [T], width: usize, height: usize) -> Result<Self> {
        Self::new(data, width, height, width)
    }

    /// Width, px.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height, px.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Elements between the starts of two consecutive rows.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Row `y` (`width` pixels); empty if `y >= height`.
    #[inline]
    pub fn row(&self, y: usize) -> &'a [T] {
        if y >= self.height {
            return &[];
        }
        let start = y * self.stride;
        self.data.get(start..start + self.width).unwrap_or(&[])
    }

    /// Fails with [`Error::TooFew`] unless the image has at least `min` rows and columns.
    pub(crate) fn require_side(&self, min: usize, what: &'static str) -> Result<()> {
        let got = if self.width < self.height { self.width } else { self.height };
        if got < min {
            return Err(Error::TooFew { what, needed: min, got });
        }
        Ok(())
    }
}
