//! Text in figures, set in DejaVu Sans by ab_glyph for every backend: text
//! widths for the layout, and on bitmaps the glyphs themselves, each at its
//! unrounded advance with its side bearing and the font's kerning.
//! Plotters' own bitmap text drops the side bearings and rounds every
//! advance down, which spreads `u1f` into `u1 f`.
//!
//! Not for SVG glyphs: an SVG names its font and the viewer sets the text.

use std::sync::OnceLock;

use ab_glyph::{Font, FontRef, Glyph, InvalidFont, PxScale, ScaleFont, point};
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};

/// DejaVu Sans (Bitstream Vera licence: fonts/DejaVu-LICENSE), the one font
/// of every figure.
const FONT: &[u8] = include_bytes!("fonts/DejaVuSans.ttf");

/// The font family every text names: DejaVu Sans (the font the PNGs are
/// set in), then the fonts that share its metrics or stand in for it.
pub const FAMILY: &str = "'DejaVu Sans', 'Bitstream Vera Sans', Arial, Helvetica, sans-serif";

/// Plotters' text size over the font size (em) it means: the SVG backend
/// writes `font-size` as the size over 1.24, and so do the bitmaps here.
const SIZE_PER_EM: f64 = 1.24;

/// DejaVu Sans's x-height, em (1120 of 2048 units): an SVG's `0.5ex`.
const X_HEIGHT: f32 = 1120.0 / 2048.0;

/// DejaVu Sans parsed once.
fn font() -> Result<&'static FontRef<'static>, InvalidFont> {
    static PARSED: OnceLock<Result<FontRef<'static>, InvalidFont>> = OnceLock::new();
    PARSED
        .get_or_init(|| FontRef::try_from_slice(FONT))
        .as_ref()
        .map_err(|error| *error)
}

/// The glyphs of `text` at `em` px per em, the pen from `x = 0` on the
/// baseline `y = 0` (advances and kerning unrounded), and the width they
/// advance.
fn glyphs(text: &str, em: f32) -> Result<(Vec<Glyph>, f32), InvalidFont> {
    let font = font()?;
    let units_per_em = font.units_per_em().ok_or(InvalidFont)?;
    let scale = PxScale::from(em * font.height_unscaled() / units_per_em);
    let scaled = font.as_scaled(scale);
    let (mut pen, mut previous) = (0.0, None);
    let mut glyphs = Vec::new();
    for c in text.chars() {
        let id = scaled.glyph_id(c);
        if let Some(previous) = previous {
            pen += scaled.kern(previous, id);
        }
        glyphs.push(id.with_scale_and_position(scale, point(pen, 0.0)));
        pen += scaled.h_advance(id);
        previous = Some(id);
    }
    Ok((glyphs, pen))
}

/// The font size of `style`, px per em.
fn em<S: BackendTextStyle>(style: &S) -> f32 {
    (style.size() / SIZE_PER_EM) as f32
}

fn font_error<E: std::error::Error + Send + Sync>(error: InvalidFont) -> DrawingErrorKind<E> {
    DrawingErrorKind::FontError(Box::new(error))
}

/// A backend whose text widths come from [`glyphs`]; on a bitmap
/// ([`Typeset::bitmap`]) its text is drawn from them too, otherwise the
/// backend writes the text itself (SVG `<text>`).
pub struct Typeset<B> {
    inner: B,
    draws_glyphs: bool,
}

impl<B: DrawingBackend> Typeset<B> {
    /// A bitmap backend: glyphs drawn here.
    pub fn bitmap(inner: B) -> Typeset<B> {
        Typeset {
            inner,
            draws_glyphs: true,
        }
    }

    /// A vector backend: text written by it.
    pub fn vector(inner: B) -> Typeset<B> {
        Typeset {
            inner,
            draws_glyphs: false,
        }
    }

    /// Draws `text` as glyph coverage on the inner backend's pixels, placed
    /// at `pos` as an SVG viewer would: `Top` puts the baseline 0.76 em
    /// below `pos`, `Center` half an x-height, `Bottom` half an x-height
    /// above.
    fn draw_glyphs<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        let em = em(style);
        let (glyphs, width) = glyphs(text, em).map_err(font_error)?;
        let anchor = style.anchor();
        let left = match anchor.h_pos {
            HPos::Left => 0.0,
            HPos::Center => -width / 2.0,
            HPos::Right => -width,
        };
        let baseline = match anchor.v_pos {
            VPos::Top => 0.76 * em,
            VPos::Center => 0.5 * X_HEIGHT * em,
            VPos::Bottom => -0.5 * X_HEIGHT * em,
        };
        let font = font().map_err(font_error)?;
        let (colour, turn) = (style.color(), style.transform());
        let mut coverage = Vec::new();
        for mut glyph in glyphs {
            glyph.position = point(glyph.position.x + left, baseline);
            if let Some(outline) = font.outline_glyph(glyph) {
                let corner = outline.px_bounds().min;
                outline.draw(|x, y, cover| {
                    coverage.push((
                        corner.x as i32 + x as i32,
                        corner.y as i32 + y as i32,
                        cover,
                    ))
                });
            }
        }
        for (x, y, cover) in coverage.into_iter().filter(|c| c.2 > 0.0) {
            let (dx, dy) = turn.transform(x, y);
            let shade = BackendColor {
                alpha: colour.alpha * f64::from(cover.min(1.0)),
                rgb: colour.rgb,
            };
            self.inner.draw_pixel((pos.0 + dx, pos.1 + dy), shade)?;
        }
        Ok(())
    }
}

impl<B: DrawingBackend> DrawingBackend for Typeset<B> {
    type ErrorType = B::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        colour: BackendColor,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_pixel(point, colour)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_path(path, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vertices: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.fill_polygon(vertices, style)
    }

    fn draw_text<S: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &S,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        if self.draws_glyphs {
            self.draw_glyphs(text, style, pos)
        } else {
            self.inner.draw_text(text, style, pos)
        }
    }

    /// Width: the glyphs' advance; height: one em.
    fn estimate_text_size<S: BackendTextStyle>(
        &self,
        text: &str,
        style: &S,
    ) -> Result<(u32, u32), DrawingErrorKind<B::ErrorType>> {
        let em = em(style);
        let (_, width) = glyphs(text, em).map_err(font_error)?;
        Ok((width.ceil() as u32, em.round() as u32))
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<B::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_font_has_every_glyph_of_tick_labels() {
        let font = font().unwrap();
        for c in "0123456789.−×⁰¹²³⁴⁵⁶⁷⁸⁹⁻".chars() {
            assert_ne!(font.glyph_id(c).0, 0, "{c}");
        }
    }

    /// Plotters' bitmap text inks a glyph from its pen position; set
    /// right, `1` (side bearing 0.11 em) starts inking 11 px later at 100 px
    /// per em.
    #[test]
    fn a_glyph_is_inked_after_its_left_side_bearing() {
        use plotters::prelude::*;
        use plotters::style::text_anchor::{HPos, Pos, VPos};
        let (width, height, pen) = (200, 150, 20);
        let mut pixels = vec![255u8; width * height * 3];
        {
            let buffer = BitMapBackend::with_buffer(&mut pixels, (width as u32, height as u32));
            let mut backend = Typeset::bitmap(buffer);
            let style = TextStyle::from((FAMILY, 100.0 * SIZE_PER_EM).into_font())
                .pos(Pos::new(HPos::Left, VPos::Center));
            backend.draw_text("1", &style, (pen, 75)).unwrap();
        }
        let inked = (0..width)
            .find(|&x| (0..height).any(|y| pixels[(y * width + x) * 3] < 128))
            .unwrap();
        let font = font().unwrap();
        let (glyphs, _) = glyphs("1", 100.0).unwrap();
        let bearing = font.as_scaled(glyphs[0].scale).h_side_bearing(glyphs[0].id);
        assert!(bearing > 10.0, "{bearing}");
        let expected = pen as f32 + bearing;
        assert!(
            (inked as f32 - expected).abs() <= 1.0,
            "{inked} vs {expected}"
        );
    }
}
